"""Fast, large arm motion (issue 13): where the offline pipeline loses to a constant-velocity Kalman smoother.

Truth: HDM05 clips per motion class (rotateArmsBothBackward, squat, kickLFront, elbowToKnee; the first `--clips`
of each subject, 1-2.5 s each) and CMU 13_29 cut into its labelled actions (arm circles, jumping jacks, twists, toe
touches, knee raises, squats; 3-9 s each, mocap6 labels), 30 Hz,
placed in the camera frame (kinect_agent.sources.mocap_truth) and measured by a simulated Kinect 2
(kinect_agent.sources.kinect_noise; `--device kinect1` for Kinect 1) at each view and seed.
Methods: raw (gaps held), One Euro, CV Kalman + RTS (bench/baselines), the pipeline offline (process()).
Per motion, view and seed (pooled over the motion's clips), then the median over seeds:
    rmse_mm       3-D RMSE over every joint-frame, mm
    arm_mm        the same over elbows, wrists and hands; rest_mm over the other joints
    elbow_deg     elbow flexion RMSE (both elbows), degrees; knee_deg the same for the knees
    removed_pct   of the arm joint-frames that are true samples (not simulated tracking loss, tracked or
                  inferred), the percentage the pipeline's outlier step removes; removed_all_pct over all joints
    lag_ms        wrist lag of the estimate behind the truth: the shift (±6 frames, parabolic peak) that maximises
                  the cross-correlation of estimated and true wrist velocity, positive = estimate late

    python bench/arms.py [--views 0 60] [--seeds 1 2 3] [--motions rotateArms squat ...] [--set NAME=VALUE ...]
"""

from __future__ import annotations

import argparse
import ast
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:  # `python bench/arms.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT_DIR))

from bench.accuracy import run_method  # noqa: E402
from kinect_agent import skeleton  # noqa: E402
from kinect_agent.body.angles import joint_angles  # noqa: E402
from kinect_agent.processing.config import PipelineConfig  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402
from kinect_agent.skeleton import NOT_TRACKED  # noqa: E402
from kinect_agent.sources.kinect_noise import add_kinect_noise  # noqa: E402
from kinect_agent.sources.mocap_truth import place_in_camera, resample  # noqa: E402

DATA_DIR = ROOT_DIR.parent / "shared" / "data"
HDM05_DIR = DATA_DIR / "hdm05"
CMU_FILE = DATA_DIR / "cmu-mocap" / "13_29.bvh"
RATE_HZ = 30.0
MOTIONS: dict[str, str | None] = {  # short name -> HDM05 folder (None: CMU 13_29)
    "rotateArms": "rotateArmsBothBackward1Reps",
    "squat": "squat1Reps",
    "kick": "kickLFront1Reps",
    "elbowToKnee": "elbowToKnee1RepsLelbowStart",
}
CMU_SEGMENTS = CMU_FILE.with_name("13_29_segments_from_mocap6.csv")  # action, ..., first/last frame at 120 Hz
CMU_ACTIONS = ("ArmCircle", "JumpJack", "Twist", "ToeTouchOneHand", "KneeRaise", "Squat")
MOTIONS.update({f"cmu_{a}": None for a in CMU_ACTIONS})
METHODS = ("raw", "one_euro", "cv_kalman_rts", "pipeline")
ARM = np.array([skeleton.INDEX[n] for n in ("ELB_L", "WRI_L", "HAN_L", "ELB_R", "WRI_R", "HAN_R")])
REST = np.setdiff1d(np.arange(skeleton.J), ARM)
WRISTS = np.array([skeleton.INDEX["WRI_L"], skeleton.INDEX["WRI_R"]])
MAX_LAG = 6
ANGLES = ("elbow_flexion_L", "elbow_flexion_R", "knee_flexion_L", "knee_flexion_R")


@dataclass
class Truth:
    """One mocap clip: motion name, clip name, t (T,) s, positions (T, J, 3) m in the mocap frame, heading deg."""

    motion: str
    name: str
    t: np.ndarray
    positions: np.ndarray
    facing: float


def cmu_segment(action: str) -> tuple[int, int]:
    """Returns (first, last + 1) frame at RATE_HZ of one labelled action of CMU 13_29 (mocap6 labels)."""
    for line in CMU_SEGMENTS.read_text(encoding="utf-8").splitlines()[1:]:
        name, _, _, first, last = line.split(",")
        if name == action:
            return int(int(first) * RATE_HZ / 120.0), int((int(last) + 1) * RATE_HZ / 120.0)
    raise ValueError(f"CMU 13_29 has no action {action!r}")


def truths(motions: list[str], clips: int) -> list[Truth]:
    """Returns the truth clips of the motions: the first `clips` HDM05 clips per subject, or a CMU 13_29 action."""
    from kinect_agent.formats import amc, bvh

    out, cmu = [], None
    for motion in motions:
        folder = MOTIONS[motion]
        if folder is None:
            if cmu is None:
                cmu = resample(bvh.read(CMU_FILE), RATE_HZ)
            first, last = cmu_segment(motion.removeprefix("cmu_"))
            t, p = cmu[0][first:last], cmu[1][first:last]
            out.append(Truth(motion, "13_29", t - t[0], p, 0.0))
            continue
        for subject in ("bd", "bk"):
            for clip in sorted((HDM05_DIR / folder).glob(f"HDM_{subject}_*.amc"))[:clips]:
                rec = amc.read(clip)
                t, p = resample(rec, RATE_HZ)
                out.append(Truth(motion, clip.stem, t, p, float(rec.meta.extra["facing_deg"])))
    return out


def measure(
    truth: Truth, k: int, view: int, seed: int, white_m: float | None = None, device: str = "kinect2"
) -> tuple[Recording, np.ndarray, np.ndarray]:
    """Returns (measured Recording, truth positions (T, J, 3) m camera frame, loss mask (T, J) bool) of one clip.

    white_m: instead of the Kinect model, independent Gaussian noise of this SD per axis (m), every joint tracked.
    """
    rec = Recording.from_positions(truth.t, place_in_camera(truth.positions, view, truth.facing))
    rec.meta.rate_hz = RATE_HZ
    rng = np.random.default_rng([seed, k, 1 if device == "kinect1" else 2, view])
    if white_m is not None:
        noisy = rec.positions + white_m * rng.standard_normal(rec.positions.shape)
        return (
            rec.replace(step=f"white noise {white_m} m", positions=noisy),
            rec.positions,
            np.zeros(noisy.shape[:2], bool),
        )
    measured, mask = add_kinect_noise(rec, device=device, view_deg=view, pose="standing", rng=rng)
    return measured, rec.positions, mask


def estimate(method: str, rec: Recording, config: PipelineConfig) -> tuple[np.ndarray, np.ndarray | None]:
    """Returns (estimate (T, J, 3) m, outlier flags (T, J) bool or None) of one method (bench.accuracy.run_method;
    "pipeline" is its pipeline_offline)."""
    return run_method("pipeline_offline" if method == "pipeline" else method, rec, config)


def wrist_lag_frames(est: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    """Returns (lag in frames weighted into the sums: numerator, weight) of the wrists' velocity cross-correlation.

    est, truth: (T, J, 3) m. The correlation c(s) = Σ v̂(t+s)·v(t) over both wrists; the peak is refined by a
    parabola. Returns (peak · energy, energy) so that clips pool by the truth's wrist speed energy.
    """
    ve, vt = np.diff(est[:, WRISTS], axis=0), np.diff(truth[:, WRISTS], axis=0)
    T = len(vt)
    if T <= 2 * MAX_LAG + 2:
        return 0.0, 0.0
    shifts = np.arange(-MAX_LAG, MAX_LAG + 1)
    c = np.array([np.sum(ve[MAX_LAG + s : T - MAX_LAG + s] * vt[MAX_LAG : T - MAX_LAG]) for s in shifts])
    i = int(np.argmax(c))
    peak = float(shifts[i])
    if 0 < i < len(c) - 1:
        den = c[i - 1] - 2 * c[i] + c[i + 1]
        if den < 0:
            peak += 0.5 * (c[i - 1] - c[i + 1]) / den
    energy = float(np.sum(vt**2))
    return peak * energy, energy


def clip_sums(
    est: np.ndarray, flags: np.ndarray | None, truth: np.ndarray, mask: np.ndarray, state: np.ndarray
) -> dict[str, float]:
    """Returns a dict of sums of one method on one clip (pooled over clips by adding)."""
    err = est - truth
    d2 = np.sum(err**2, axis=-1)  # (T, J)
    r2 = np.sum((err - err.mean(axis=0)) ** 2, axis=-1)  # (T, J) each joint's mean error removed
    true_sample = ~mask & (state != NOT_TRACKED)
    lag_num, lag_w = wrist_lag_frames(est, truth)
    a_est, a_true = joint_angles(est), joint_angles(truth)
    da = {n: a_est[n] - a_true[n] for n in ANGLES}
    s = {
        "sq": d2.sum(), "n": d2.size, "sq_arm": d2[:, ARM].sum(), "n_arm": d2[:, ARM].size,
        "sq_rest": d2[:, REST].sum(), "n_rest": d2[:, REST].size, "sq_rand": r2.sum(), "sq_rand_arm": r2[:, ARM].sum(),
        "sq_elbow": sum(np.nansum(da[n] ** 2) for n in ANGLES[:2]), "n_elbow": 2 * len(est),
        "sq_knee": sum(np.nansum(da[n] ** 2) for n in ANGLES[2:]), "n_knee": 2 * len(est),
        "lag_num": lag_num, "lag_w": lag_w,
        "true_arm": true_sample[:, ARM].sum(), "true_all": true_sample.sum(), "rm_arm": 0, "rm_all": 0,
    }  # fmt: skip
    if flags is not None:
        s["rm_arm"] = (flags & true_sample)[:, ARM].sum()
        s["rm_all"] = (flags & true_sample).sum()
    return s


def metrics(s: dict[str, Any]) -> dict[str, float]:
    """Returns the reported metrics of pooled sums."""
    return {
        "rmse_mm": 1e3 * np.sqrt(s["sq"] / s["n"]),
        "arm_mm": 1e3 * np.sqrt(s["sq_arm"] / s["n_arm"]),
        "rest_mm": 1e3 * np.sqrt(s["sq_rest"] / s["n_rest"]),
        "random_mm": 1e3 * np.sqrt(s["sq_rand"] / s["n"]),
        "random_arm_mm": 1e3 * np.sqrt(s["sq_rand_arm"] / s["n_arm"]),
        "elbow_deg": float(np.sqrt(s["sq_elbow"] / s["n_elbow"])),
        "knee_deg": float(np.sqrt(s["sq_knee"] / s["n_knee"])),
        "removed_pct": 100.0 * s["rm_arm"] / max(s["true_arm"], 1),
        "removed_all_pct": 100.0 * s["rm_all"] / max(s["true_all"], 1),
        "lag_ms": 1e3 / RATE_HZ * s["lag_num"] / max(s["lag_w"], 1e-12),
    }


def run(
    motions: list[str],
    views: list[int],
    seeds: list[int],
    config: PipelineConfig,
    clips: int = 3,
    white_m: float | None = None,
    device: str = "kinect2",
) -> dict[tuple[str, int], dict[str, dict[str, float | list[float]]]]:
    """Returns {(motion, view): {method: {metric: median over seeds, "rmse_mm_seeds": [RMSE mm of each seed]}}}."""
    clips_all = truths(motions, clips)
    per_seed: dict[tuple[str, int, str], list[dict[str, float]]] = {}
    for view in views:
        for seed in seeds:
            sums: dict[tuple[str, str], dict[str, Any]] = {}
            for k, truth in enumerate(clips_all):
                measured, pos, mask = measure(truth, k, view, seed, white_m, device)
                for method in METHODS:
                    est, flags = estimate(method, measured, config)
                    one = clip_sums(est, flags, pos, mask, measured.state)
                    acc = sums.setdefault((truth.motion, method), dict.fromkeys(one, 0.0))
                    for key, v in one.items():
                        acc[key] += float(v)
            for (motion, method), s in sums.items():
                per_seed.setdefault((motion, view, method), []).append(metrics(s))
    out: dict[tuple[str, int], dict[str, dict[str, float | list[float]]]] = {}
    for (motion, view, method), runs in per_seed.items():
        med: dict[str, float | list[float]] = {key: float(np.median([r[key] for r in runs])) for key in runs[0]}
        med["rmse_mm_seeds"] = [round(r["rmse_mm"], 1) for r in runs]
        out.setdefault((motion, view), {})[method] = med
    return out


COLUMNS = (  # (header, metric, methods shown, decimals)
    ("RMSE mm raw / One Euro / CV / **pipeline**", "rmse_mm", ("raw", "one_euro", "cv_kalman_rts", "pipeline"), 1),
    ("arms mm One Euro / CV / pipeline", "arm_mm", ("one_euro", "cv_kalman_rts", "pipeline"), 1),
    ("rest mm CV / pipeline", "rest_mm", ("cv_kalman_rts", "pipeline"), 1),
    ("random part mm raw / CV / pipeline", "random_mm", ("raw", "cv_kalman_rts", "pipeline"), 1),
    ("random part arms mm CV / pipeline", "random_arm_mm", ("cv_kalman_rts", "pipeline"), 1),
    ("elbow° One Euro / CV / pipeline", "elbow_deg", ("one_euro", "cv_kalman_rts", "pipeline"), 1),
    ("knee° One Euro / CV / pipeline", "knee_deg", ("one_euro", "cv_kalman_rts", "pipeline"), 1),
    ("wrist lag ms CV / pipeline", "lag_ms", ("cv_kalman_rts", "pipeline"), 0),
    ("true arm (all) samples removed %", "removed_pct", ("pipeline",), 2),
)


def print_results(results: dict[tuple[str, int], dict[str, Any]]) -> None:
    """Prints one markdown table: per motion and view, the medians over seeds of COLUMNS, and the pipeline's RMSE
    per seed."""
    print("| motion | view | " + " | ".join(c[0] for c in COLUMNS) + " | pipeline RMSE per seed |")
    print("|---|---|" + "---|" * (len(COLUMNS) + 1))
    for (motion, view), m in results.items():
        cells = [" / ".join(f"{m[k][metric]:.{dec}f}" for k in methods) for _, metric, methods, dec in COLUMNS]
        cells[-1] += f" ({m['pipeline']['removed_all_pct']:.2f})"
        seeds = ", ".join(map(str, m["pipeline"]["rmse_mm_seeds"]))
        print(f"| {motion} | {view}° | " + " | ".join(cells) + f" | {seeds} |")


def config_from(overrides: list[str]) -> PipelineConfig:
    """Returns PipelineConfig(**overrides) from NAME=VALUE strings (Python literals: 0.2, None, True, (1, 2))."""
    kwargs = {}
    for item in overrides:
        name, sep, text = item.partition("=")
        if not sep:
            raise ValueError(f"--set {item!r}: expected NAME=VALUE")
        try:
            kwargs[name] = ast.literal_eval(text)
        except (ValueError, SyntaxError):
            kwargs[name] = text
    return PipelineConfig(**kwargs)  # checks each field's range, naming the field


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--motions", nargs="+", default=list(MOTIONS), choices=list(MOTIONS))
    parser.add_argument("--views", nargs="+", type=int, default=[0, 60])
    parser.add_argument("--seeds", nargs="+", type=int, default=[1, 2, 3])
    parser.add_argument("--clips", type=int, default=3, help="HDM05 clips per subject and motion")
    parser.add_argument("--device", default="kinect2", choices=["kinect2", "kinect1"])
    parser.add_argument("--white", type=float, default=None, help="white noise SD per axis, m, instead of Kinect's")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    args = parser.parse_args(argv)
    config = config_from(args.set)
    started = time.perf_counter()
    results = run(args.motions, args.views, args.seeds, config, args.clips, args.white, args.device)
    print(f"overrides: {args.set or 'none'}\n")
    print_results(results)
    print(f"\n({time.perf_counter() - started:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
