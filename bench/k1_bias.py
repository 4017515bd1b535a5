"""Where the offline pipeline's position bias against CV Kalman + RTS comes from (issue 13, simulated Kinect 1).

Two studies on bench/accuracy.py's per-motion clips (same noise per seed, clip, device and view):

rows (default): per motion, view and seed, RMSE and its bias/random parts (body frame, error_parts.py), mm, of
    raw, CV Kalman + RTS, One Euro, the offline pipeline, CV Kalman + RTS run on the pipeline's outlier-removed input
    ("CV on clean"), and oracle clean (bench/error_floor.py: truth + the Kinect's error with every tracking-loss
    outlier replaced by the interpolated clean error). Then the same methods on a counterfactual of the simulator's
    tracking-loss law: kinect_noise draws each outlier around the Kinect's *biased* estimate (truth + clean offset +
    random jump; since issue 24 decision 4, 2026-11-28); "alt" moves each outlier back by the Kinect's clean error
    at that frame (interpolated from the clean neighbours, as oracle clean), i.e. draws the same jump around the
    *truth*, as the simulator did before, so outliers that a method keeps pull its mean error toward zero. (Before
    decision 4 "alt" went the other way: from the truth to the biased position.)
joints: per joint, the bias/RMSE (mm) of raw, CV, oracle clean and offline variants whose fixed segment lengths
    (passes 3-4) are replaced by the truth's median bone lengths ("truth lengths") or the median measured lengths
    ("measured lengths"), and the least-squares re-fit of the bone vectors given the smoothed rotations
    (bench/bone_refit.py, "refit"); then the bone lengths (mm): truth, measured median, pipeline.

    python bench/k1_bias.py [--motions NAME ...] [--views 0 60] [--seeds 1 2 3] [--device kinect1] [--json OUT]
    python bench/k1_bias.py --study joints --motions hdm05_squat1Reps ui_prmd_m05 ui_prmd_m08 --seeds 1
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any
from unittest.mock import patch

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:
    sys.path.insert(0, str(ROOT_DIR))

from bench.accuracy import RATE_HZ, Case, MotionSums, motion_cases, motions, run_method  # noqa: E402
from bench.baselines import cv_kalman_rts  # noqa: E402
from bench.baselines._common import hold_last  # noqa: E402
from bench.bone_refit import refit_bones  # noqa: E402
from bench.error_floor import clean_error, oracle_estimate  # noqa: E402
from kinect_agent import skeleton  # noqa: E402
from kinect_agent.body.angles import joint_angles  # noqa: E402
from kinect_agent.evaluation.error_parts import JointErrorSums  # noqa: E402
from kinect_agent.processing import chain_filter  # noqa: E402
from kinect_agent.processing.combined_outliers import remove_outliers_combined  # noqa: E402
from kinect_agent.processing.config import PipelineConfig  # noqa: E402
from kinect_agent.processing.ik import inverse_kinematics  # noqa: E402
from kinect_agent.processing.pipeline import observations, smooth  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402

ELBOWS = ("elbow_flexion_L", "elbow_flexion_R")
ROW_METHODS = ("raw", "cv_kalman_rts", "one_euro", "pipeline_offline")


def alt_outliers(case: Case) -> np.ndarray:
    """Returns (T, J, 3) m: the measured positions with every tracking-loss outlier moved back by the clean error
    there (its jump drawn around the truth instead of the Kinect's biased estimate)."""
    m = case.measured
    shift = clean_error(m.positions, m.state, case.truth, case.mask)
    return np.where(case.mask[..., None], m.positions - shift, m.positions)


def study_rows(args: argparse.Namespace) -> list[dict[str, Any]]:
    config = PipelineConfig()
    rows = []
    print("| motion | view | seed | raw | CV+RTS | One Euro | offline | CV on clean | oracle clean | alt: raw "
          "| alt: CV+RTS | alt: One Euro | alt: offline |")  # fmt: skip
    print("|---|---|---|" + "---|" * 10)
    for motion in [m for m in motions() if not args.motions or m.name in args.motions]:
        for view in args.views:
            for seed in args.seeds:
                sums: dict[str, MotionSums] = {}

                def add(name: str, case: Case, est: np.ndarray, sums: dict[str, MotionSums] = sums) -> None:
                    sums.setdefault(name, MotionSums()).add_case(case, est)

                for case in motion_cases(motion, view, seed, args.device):
                    m = case.measured
                    for name in ROW_METHODS:
                        add(name, case, run_method(name, m, config)[0])
                    clean, _ = remove_outliers_combined(m, config)
                    add("cv_on_clean", case, hold_last(cv_kalman_rts(m.t, clean.positions)))
                    add("oracle_clean", case, oracle_estimate(m.positions, m.state, case.truth, case.mask, RATE_HZ))
                    alt = m.replace(step="outliers around the truth", positions=alt_outliers(case))
                    for name in ROW_METHODS:
                        add(f"alt_{name}", case, run_method(name, alt, config)[0])
                metrics = {k: s.metrics() for k, s in sums.items()}
                rows.append({"motion": motion.name, "view_deg": view, "seed": seed, "device": args.device,
                             "methods": metrics})  # fmt: skip
                order = [*ROW_METHODS[:3], "pipeline_offline", "cv_on_clean", "oracle_clean",
                         *(f"alt_{n}" for n in ROW_METHODS)]  # fmt: skip
                cells = [f"{metrics[k]['rmse_mm']:.1f} ({metrics[k]['bias_mm']:.1f}/{metrics[k]['random_mm']:.1f})"
                         for k in order]  # fmt: skip
                print(f"| {motion.name} | {view}° | {seed} | " + " | ".join(cells) + " |", flush=True)
    return rows


def summarise(rows: list[dict[str, Any]]) -> None:
    """Prints per motion and view, each seed's margins (offline minus CV+RTS / One Euro RMSE, mm) under the simulator's
    outlier law and under "alt", and the medians over seeds of the bias differences (mm)."""
    groups: dict[tuple[str, int], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((r["motion"], r["view_deg"]), []).append(r)

    def seeds(runs: list[dict[str, Any]], a: str, b: str, key: str = "rmse_mm") -> str:
        return "/".join(f"{r['methods'][a][key] - r['methods'][b][key]:+.1f}" for r in runs)

    def med(runs: list[dict[str, Any]], a: str, b: str, key: str) -> float:
        return float(np.median([r["methods"][a][key] - r["methods"][b][key] for r in runs]))

    print("\n| motion | view | offline − CV+RTS | offline − One Euro | alt: offline − CV+RTS | alt: offline − One Euro "
          "| bias: oracle clean − raw | bias: offline − oracle clean | random: offline − CV on clean |")  # fmt: skip
    print("|---|---|" + "---|" * 7)
    fails = {"now": [0, 0], "alt": [0, 0]}
    off, alt = "pipeline_offline", "alt_pipeline_offline"
    for (name, view), runs in groups.items():
        for law, prefix in (("now", ""), ("alt", "alt_")):
            for i, base in enumerate(("cv_kalman_rts", "one_euro")):
                m = [r["methods"][prefix + off]["rmse_mm"] - r["methods"][prefix + base]["rmse_mm"] for r in runs]
                fails[law][i] += any(x >= 0 for x in m)
        cells = [
            seeds(runs, off, "cv_kalman_rts"),
            seeds(runs, off, "one_euro"),
            seeds(runs, alt, "alt_cv_kalman_rts"),
            seeds(runs, alt, "alt_one_euro"),
            f"{med(runs, 'oracle_clean', 'raw', 'bias_mm'):+.1f}",
            f"{med(runs, off, 'oracle_clean', 'bias_mm'):+.1f}",
            f"{med(runs, off, 'cv_on_clean', 'random_mm'):+.1f}",
        ]
        print(f"| {name} | {view}° | " + " | ".join(cells) + " |")
    n = len(groups)
    print(f"\nrows failing on at least one seed, of {n}: RMSE < CV+RTS {fails['now'][0]}, < One Euro "
          f"{fails['now'][1]}; with the outliers' jumps drawn around the truth (alt): {fails['alt'][0]} and "
          f"{fails['alt'][1]}")  # fmt: skip


# ------------------------------------------------------------------------------------------------ joints study

_override: dict[str, np.ndarray | None] = {"lengths": None}
_estimated: list[np.ndarray] = []
_fixed = chain_filter.ChainFilter.with_lengths_fixed


def _with_lengths_fixed(
    self: chain_filter.ChainFilter, lengths: np.ndarray, config: PipelineConfig
) -> chain_filter.ChainFilter:
    """ChainFilter.with_lengths_fixed while study_joints runs: records the lengths of passes 3-4, swaps them for
    _override["lengths"] when set."""
    _estimated.append(np.array(lengths))
    return _fixed(self, lengths if _override["lengths"] is None else _override["lengths"], config)


def bone_median(positions: np.ndarray) -> np.ndarray:
    """Returns (19,) m, each bone's median length over the frames where both ends are finite."""
    return np.nanmedian(skeleton.bone_lengths(positions), axis=0)


def offline_variant(rec: Recording, config: PipelineConfig, lengths: np.ndarray | None, refit: bool) -> np.ndarray:
    """Returns (T, J, 3) m: the offline pipeline's positions (offset_model off), with passes 3-4 on `lengths` when
    given and the bone vectors re-fitted afterwards when refit."""
    clean, _ = remove_outliers_combined(rec, config)
    ik = inverse_kinematics(clean.positions)
    _override["lengths"] = lengths
    try:
        root, fixed, theta, _ = smooth(clean, ik, config)
    finally:
        _override["lengths"] = None
    if lengths is not None:
        fixed = lengths
    model = ik.model
    if refit:
        T = rec.n_frames
        z, seen, r_diag = observations(clean, config)
        weights = np.where(seen[:, ::3], config.sigma_tracked_m**2 / r_diag[:, ::3], 0.0)
        out = refit_bones(model, root, fixed, theta, z.reshape(T, skeleton.J, 3), weights)
        model, fixed, root = out.model, out.lengths, out.root
    return model.positions(root, np.broadcast_to(fixed, (rec.n_frames, len(fixed))), theta)


def study_joints(args: argparse.Namespace) -> None:
    swapped = patch.object(chain_filter.ChainFilter, "with_lengths_fixed", _with_lengths_fixed)
    swapped.start()
    config = PipelineConfig()
    for motion in [m for m in motions() if not args.motions or m.name in args.motions]:
        for view in args.views:
            sums: dict[str, JointErrorSums] = {}
            lens: dict[str, list[np.ndarray]] = {"truth": [], "measured median": [], "pipeline": []}
            angles: dict[tuple[str, str], list[np.ndarray]] = {}
            for seed in args.seeds:
                for case in motion_cases(motion, view, seed, args.device):
                    m = case.measured
                    clean, _ = remove_outliers_combined(m, config)
                    truth_len, raw_len = bone_median(case.truth), bone_median(clean.positions)
                    ests = {name: run_method(name, m, config)[0] for name in ("raw", "cv_kalman_rts")}
                    ests["oracle clean"] = oracle_estimate(m.positions, m.state, case.truth, case.mask, RATE_HZ)
                    _estimated.clear()
                    ests["offline"] = offline_variant(m, config, None, False)
                    lens["pipeline"].append(_estimated[0])
                    lens["truth"].append(truth_len)
                    lens["measured median"].append(raw_len)
                    ests["truth lengths"] = offline_variant(m, config, truth_len, False)
                    ests["measured lengths"] = offline_variant(m, config, raw_len, False)
                    ests["refit"] = offline_variant(m, config, None, True)
                    a_true = joint_angles(case.truth)
                    for name, est in ests.items():
                        sums.setdefault(name, JointErrorSums.zeros(skeleton.J)).add(est, case.truth)
                        a_est = joint_angles(est)
                        for angle in ELBOWS:
                            angles.setdefault((name, angle), []).append(a_est[angle] - a_true[angle])
            print(f"\n#### {motion.name} {view}°, {args.device}, seeds {args.seeds}: bias / RMSE per joint, mm\n")
            names = list(sums)
            print("| joint | " + " | ".join(names) + " |")
            print("|---|" + "---|" * len(names))
            per = {n: s.rms_mm() for n, s in sums.items()}
            for j, joint in enumerate(skeleton.JOINTS):
                print(f"| {joint} | " + " | ".join(f"{per[n]['bias_mm'][j]:.0f} / {per[n]['rmse_mm'][j]:.0f}"
                                                    for n in names) + " |")  # fmt: skip
            pooled = {n: s.pooled() for n, s in sums.items()}
            print("| **all** (random) | " + " | ".join(
                f"**{pooled[n]['bias_mm']:.1f} / {pooled[n]['rmse_mm']:.1f}** ({pooled[n]['random_mm']:.1f})"
                for n in names) + " |")  # fmt: skip
            print("\n| elbow flexion error, ° (mean ± SD over frames) | " + " | ".join(names) + " |")
            print("|---|" + "---|" * len(names))
            for angle in ELBOWS:
                cells = []
                for n in names:
                    d = np.concatenate(angles[n, angle])
                    cells.append(f"{np.nanmean(d):+.1f} ± {np.nanstd(d):.1f}")
                print(f"| {angle} | " + " | ".join(cells) + " |")
            print("\n| bone (child joint) | " + " | ".join(lens) + " |\n|---|" + "---|" * len(lens))
            mean = {k: 1e3 * np.nanmean(np.array(v), axis=0) for k, v in lens.items()}
            for k, (_, c) in enumerate(skeleton.BONES):
                print(f"| {skeleton.JOINTS[c]} | " + " | ".join(f"{mean[n][k]:.0f}" for n in mean) + " |")
    swapped.stop()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--study", choices=("rows", "joints"), default="rows")
    parser.add_argument("--motions", nargs="*", default=[], help="motion names (default: every motion)")
    parser.add_argument("--views", type=int, nargs="+", default=[0, 60])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--device", choices=("kinect1", "kinect2"), default="kinect1")
    parser.add_argument("--json", help="rows study: also write the rows to this file")
    parser.add_argument("--summarise", metavar="JSON", help="rows study: only print the summary of a --json file")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    if args.summarise:
        summarise(json.loads(Path(args.summarise).read_text()))
    elif args.study == "joints":
        study_joints(args)
    else:
        rows = study_rows(args)
        summarise(rows)
        if args.json:
            Path(args.json).write_text(json.dumps(rows, indent=1))
    print(f"\n({time.perf_counter() - started:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
