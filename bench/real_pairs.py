"""Accuracy of real Kinect v2 recordings, raw and filtered, against simultaneous Vicon joint-centre estimates.

Pairs: KERAAL group 3 (/work/shared/data/keraal/kinect_vicon_pairs/G3-Kinect-*.txt with the G3-Vicon-*.txt of the
    same trial; kinect_agent.formats.keraal and keraal_vicon). Rates are not in the files: Kinect 30 Hz and Vicon
    60 Hz assumed (each Vicon file has 1.98-2.02 x the rows of its Kinect file; the lag fitted on each half of a
    pair checks the ratio). UI-PRMD is not used: its Kinect and Vicon episodes were segmented separately (same
    episode: 2.1-2.4 s of Kinect against 1.6-2.9 s of Vicon), so they are not time-matched pairs.
Truth: the Vicon reader's joint centres (SCoRE from 17 rigid bodies). "Well-estimated" joints are the SCoRE joints
    not in meta.extra["fallback_joints"], plus ROOT (mid-hips) when both hips are, plus SPINE (mid ROOT-NECK) when
    ROOT and NECK are. HEAD, HAN_*, FOO_* are rigid-body target positions, not joint centres: never well-estimated.
Alignment, per pair (kinect_agent.evaluation.align, shared with `kinect-agent evaluate`):
    time   the Vicon joints are linearly interpolated at t_kinect + lag (the Kinect frames stay as recorded, so every
           method sees the real 30 Hz data); coarse lag: maximum cross-correlation of the summed speed of the
           well-estimated joints (speed is invariant to the unknown rigid transform), over +-MAX_LAG_S in 1/120 s
           steps; fine lag: minimum trimmed registration RMS within +-2 frames of it.
    space  one rigid transform (Kabsch, no scale) taking Vicon into the Kinect camera frame, fitted on the raw Kinect
           joint-frames of the well-estimated joints, refitted twice after dropping the worst TRIM of residuals.
           It is fitted on raw Kinect and then used for every method. It absorbs the mean offset of the registered
           joints (the paper calibrated the two systems independently; its offsets include that bias, ours do not).
Metrics (per joint; pooled over the well-estimated joint-frames of all pairs), mm unless stated:
    offset mean / SD   mean and SD of the offset distance |estimate - Vicon| (the paper's measure, section 3.1)
    rmse               sqrt(mean |estimate - Vicon|^2)
    seg SD             SD over time of each of the 14 table segments' lengths, mean over segments (Vicon's own for
                       reference; the truth's is 0 only where SCoRE fits hold)
    elbow RMSE (deg)   elbow flexion (kinect_agent.body.angles) against Vicon's, sides with SHO, ELB, WRI well
    gain               the paper's outlier-removal gain: raw offset mean and SD before vs after dropping the
                       joint-frames the pipeline flags (outlier_prob > threshold, kinect_agent.processing.outliers);
                       "oracle": the paper's own setting, the Gaussian + uniform mixture fitted to the offsets
                       against Vicon (kinect_agent.processing.outliers.fit_mixture on the 3-D offsets per joint and
                       pair, with the pipeline's floors: sigma >= outlier_min_sigma_m, box >= outlier_min_range_m,
                       rho >= 0.5),
                       posterior(uniform) > 0.5 removed.

    .venv/bin/python bench/real_pairs.py [--json OUT] [--set NAME=VALUE ...]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:
    sys.path.insert(0, str(ROOT_DIR))

from bench.accuracy import METHODS, outlier_flags, pipeline_config, run_method  # noqa: E402
from bench.accuracy_tables import cell  # noqa: E402
from kinect_agent import skeleton  # noqa: E402
from kinect_agent.body.angles import joint_angles  # noqa: E402
from kinect_agent.evaluation.align import Alignment, interpolate, speed_signal  # noqa: E402, F401
from kinect_agent.evaluation.align import align as evaluation_align  # noqa: E402
from kinect_agent.evaluation.pairs import SCORE_JOINTS, well_estimated  # noqa: E402, F401
from kinect_agent.evaluation.register import TRIM, kabsch, robust_kabsch, rotation_deg  # noqa: E402, F401
from kinect_agent.processing.config import PipelineConfig  # noqa: E402
from kinect_agent.processing.outliers import fit_mixture  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402
from kinect_agent.skeleton import NOT_TRACKED  # noqa: E402

DATA_DIR = Path(os.environ.get("COACH_SHARED_DIR", ROOT_DIR.parent / "shared")) / "data"  # as tests/conftest.py
PAIRS_DIR = DATA_DIR / "keraal" / "kinect_vicon_pairs"
RATE_HZ = 30.0  # common grid: the Kinect frames (KERAAL Kinect, 30 Hz assumed)
VICON_RATE_HZ = 60.0  # KERAAL Vicon, assumed (kinect_agent.formats.keraal_vicon)
MAX_LAG_S = 2.0
LAG_STEP_S = 1.0 / 120.0
TARGET_JOINTS = ("HEAD", "HAN_L", "HAN_R", "FOO_L", "FOO_R")
ARM_JOINTS = ("SHO_L", "ELB_L", "WRI_L", "SHO_R", "ELB_R", "WRI_R")
PAPER_GAIN_PCT = {"mean": (2.0, 8.0), "sd": (23.0, 49.0)}  # reference README: outlier removal gain ranges


# ----------------------------------------------------------------------------------------------- alignment


def align(kinect: Recording, vicon: Recording, joints: np.ndarray, max_lag_s: float = MAX_LAG_S) -> Alignment:
    """Finds the lag and rigid transform taking vicon (any rate) onto kinect's frames, using the joints (J,) bool
    (kinect_agent.evaluation.align.align without the independent RMS lag and, as in the runs bench/README.md reports,
    without the running median before the speeds)."""
    return evaluation_align(kinect, vicon, joints, max_lag_s=max_lag_s, check=False, despike_s=0.0)


def registered_truth(kinect: Recording, vicon: Recording, al: Alignment) -> np.ndarray:
    """Returns the Vicon joints (T, J, 3) m at the Kinect frames, in the Kinect camera frame; NaN outside overlap."""
    return al.truth(kinect, vicon)


# ----------------------------------------------------------------------------------------------- one pair


def read_pair(kinect_path: Path) -> tuple[Recording, Recording]:
    """Reads a KERAAL Kinect file and its Vicon file (same name with Kinect -> Vicon)."""
    from kinect_agent.formats import keraal, keraal_vicon

    vicon_path = kinect_path.with_name(kinect_path.name.replace("-Kinect-", "-Vicon-"))
    return keraal.read(kinect_path), keraal_vicon.read(vicon_path)


def pair_paths() -> list[Path]:
    return sorted(p for p in PAIRS_DIR.glob("G3-Kinect-*.txt")
                  if p.with_name(p.name.replace("-Kinect-", "-Vicon-")).is_file())  # fmt: skip


def evaluate_pair(kinect: Recording, vicon: Recording, methods: tuple[str, ...] = METHODS,
                  config: PipelineConfig | None = None) -> dict[str, Any]:  # fmt: skip
    """Aligns one pair and runs every method; returns alignment numbers and per-method arrays (not JSON-ready).

    Keys: name, alignment, good (J,) bool, truth (T, J, 3), overlap (T,) bool, est {method: (T, J, 3)},
    flags (T, J) bool (pipeline offline), seconds {method: s}.
    """
    config = config or PipelineConfig()
    good = well_estimated(vicon.meta.extra.get("fallback_joints", []))
    al = align(kinect, vicon, good)
    truth = registered_truth(kinect, vicon, al)
    overlap = np.all(np.isfinite(truth[:, good]), axis=(1, 2))
    est, seconds, flags = {}, {}, None
    for name in methods:
        start = time.perf_counter()
        est[name], f = run_method(name, kinect, config)
        seconds[name] = time.perf_counter() - start
        if name == "pipeline_offline":
            flags = f
    if flags is None:  # the gain still needs the pipeline's outlier flags
        flags = outlier_flags(process(kinect, config=config), kinect, config)
    return {
        "name": kinect.meta.extra.get("recording", "pair"), "alignment": al, "good": good, "truth": truth,
        "overlap": overlap, "est": est, "flags": flags, "seconds": seconds, "kinect": kinect,
        "fallback": list(vicon.meta.extra.get("fallback_joints", [])), "vicon_frames": vicon.n_frames,
    }  # fmt: skip


# ----------------------------------------------------------------------------------------------- metrics


def _stats(d: np.ndarray) -> dict[str, float | int | None]:
    d = d[np.isfinite(d)]
    if d.size == 0:
        return {"mean_mm": None, "sd_mm": None, "rmse_mm": None, "median_mm": None, "n": 0}
    return {"mean_mm": 1e3 * float(d.mean()), "sd_mm": 1e3 * float(d.std()),
            "rmse_mm": 1e3 * float(np.sqrt(np.mean(d**2))), "median_mm": 1e3 * float(np.median(d)),
            "n": int(d.size)}  # fmt: skip


def offsets(pair: dict[str, Any], name: str) -> np.ndarray:
    """Returns (T', J) m: the offset distance of one method on the overlapping frames of a pair."""
    return np.linalg.norm(pair["est"][name] - pair["truth"], axis=-1)[pair["overlap"]]


def _gain(before: np.ndarray, after: np.ndarray) -> dict[str, float | None]:
    if before.size < 2 or after.size < 2:
        return {"mean_pct": None, "sd_pct": None}
    return {
        "mean_pct": 100.0 * (1.0 - after.mean() / before.mean()),
        "sd_pct": 100.0 * (1.0 - after.std() / before.std()),
    }


def summarise(
    pairs: list[dict[str, Any]], methods: tuple[str, ...], config: PipelineConfig | None = None
) -> dict[str, Any]:
    """Returns JSON-ready results: per pair alignment, per method pooled and per joint metrics, angles, seg SD, gain."""
    config = config or PipelineConfig()
    out: dict[str, Any] = {"pairs": [], "methods": {}, "per_joint": {}, "gain": {}}
    for p in pairs:
        al = p["alignment"]
        k = p["kinect"]
        out["pairs"].append({
            "name": p["name"], "kinect_frames": k.n_frames, "vicon_frames": p["vicon_frames"],
            "rows_ratio": p["vicon_frames"] / k.n_frames, "overlap_frames": int(p["overlap"].sum()),
            "fallback_joints": p["fallback"],
            "well_estimated": [j for j, g in zip(skeleton.JOINTS, p["good"], strict=True) if g],
            "lag_s": al.lag_s, "lag_xcorr_s": al.lag_xcorr_s, "xcorr": al.xcorr, "lag_halves_s": list(al.lag_halves_s),
            "rotation_deg": rotation_deg(al.R), "translation_m": al.t.tolist(), "registration_rms_mm": 1e3 * al.rms_m,
            "n_flagged": int(p["flags"].sum()), "n_joint_frames": int(p["flags"].size),
            "rmse_mm": {m: _stats(offsets(p, m)[:, p["good"]].ravel())["rmse_mm"] for m in methods},
            "median_mm": {m: _stats(offsets(p, m)[:, p["good"]].ravel())["median_mm"] for m in methods},
        })  # fmt: skip
    for name in (*methods, "vicon"):
        pooled: list[np.ndarray] = []
        per_joint: dict[str, list[np.ndarray]] = {j: [] for j in skeleton.JOINTS}
        per_joint_all: dict[str, list[np.ndarray]] = {j: [] for j in skeleton.JOINTS}
        arm_pooled = []
        seg_sd, ang_sq = [], []
        for p in pairs:
            ov = p["overlap"]
            est = p["truth"][ov] if name == "vicon" else p["est"][name][ov]
            truth = p["truth"][ov]
            d = np.linalg.norm(est - truth, axis=-1)
            good = p["good"]
            pooled.append(d[:, good].ravel())
            arm_pooled.append(d[:, [skeleton.INDEX[j] for j in ARM_JOINTS if good[skeleton.INDEX[j]]]].ravel())
            for j, jn in enumerate(skeleton.JOINTS):
                (per_joint if good[j] else per_joint_all)[jn].append(d[:, j])
            seg_sd.append(np.nanstd(skeleton.segment_lengths(est), axis=0))
            a_est, a_true = joint_angles(est), joint_angles(truth)
            for side in ("L", "R"):
                if all(good[skeleton.INDEX[f"{n}_{side}"]] for n in ("SHO", "ELB", "WRI")):
                    da = a_est[f"elbow_flexion_{side}"] - a_true[f"elbow_flexion_{side}"]
                    ang_sq.append(da[np.isfinite(da)])
        ang = np.concatenate(ang_sq) if ang_sq else np.zeros(0)
        seg = np.array(seg_sd)  # (pairs, 14)
        out["methods"][name] = {
            **_stats(np.concatenate(pooled)),
            "arm": _stats(np.concatenate(arm_pooled)),
            "segment_sd_mm": 1e3 * float(np.nanmean(seg)),
            "arm_segment_sd_mm": 1e3 * float(np.nanmean(seg[:, [skeleton.SEGMENT_NAMES.index(s) for s in
                                                               ("ARM_UP_L", "ARM_LO_L", "ARM_UP_R", "ARM_LO_R")]])),
            "elbow_rmse_deg": float(np.sqrt(np.mean(ang**2))) if ang.size else None,
            "seconds": float(sum(p["seconds"].get(name, 0.0) for p in pairs)),
        }  # fmt: skip
        if name == "vicon":
            continue
        out["per_joint"][name] = {}
        for jn in skeleton.JOINTS:
            if per_joint[jn]:
                out["per_joint"][name][jn] = {**_stats(np.concatenate(per_joint[jn])), "well": len(per_joint[jn])}
            else:
                out["per_joint"][name][jn] = {**_stats(np.concatenate(per_joint_all[jn])), "well": 0}
    # the paper's outlier-removal gain on raw offsets (present joint-frames of the well-estimated joints)
    before: dict[str, list[np.ndarray]] = {j: [] for j in skeleton.JOINTS}
    after: dict[str, list[np.ndarray]] = {j: [] for j in skeleton.JOINTS}
    oracle: dict[str, list[np.ndarray]] = {j: [] for j in skeleton.JOINTS}
    n_flag = n_oracle = n_all = 0
    for p in pairs:
        ov = p["overlap"]
        k = p["kinect"]
        present = (k.state != NOT_TRACKED)[ov]
        flags = p["flags"][ov]
        err = (k.positions - p["truth"])[ov]  # raw offsets, NaN where untracked
        d = np.linalg.norm(err, axis=-1)
        mix = fit_mixture(
            np.where(present[..., None], err, np.nan),
            min_sigma=config.outlier_min_sigma_m,
            min_width=config.outlier_min_range_m,
            min_rho=0.5,
        )  # the pipeline's mixture settings
        post = mix.posterior_uniform(np.where(present[..., None], err, np.nan))
        o_flags = np.nan_to_num(post, nan=0.0) > 0.5
        for j, jn in enumerate(skeleton.JOINTS):
            if not p["good"][j]:
                continue
            before[jn].append(d[present[:, j], j])
            after[jn].append(d[present[:, j] & ~flags[:, j], j])
            oracle[jn].append(d[present[:, j] & ~o_flags[:, j], j])
            n_flag += int(np.sum(flags[:, j] & present[:, j]))
            n_oracle += int(np.sum(o_flags[:, j] & present[:, j]))
            n_all += int(present[:, j].sum())
    gains, o_gains = [], []
    for jn in skeleton.JOINTS:
        if before[jn]:
            b, a, o = (np.concatenate(x[jn]) for x in (before, after, oracle))
            gains.append(_gain(b, a))
            o_gains.append(_gain(b, o))
            out["gain"][jn] = {"before": _stats(b), "after": _stats(a), "oracle_after": _stats(o),
                               "gain": gains[-1], "oracle_gain": o_gains[-1]}  # fmt: skip
    allb = np.concatenate([np.concatenate(before[j]) for j in skeleton.JOINTS if before[j]])
    alla = np.concatenate([np.concatenate(after[j]) for j in skeleton.JOINTS if after[j]])
    allo = np.concatenate([np.concatenate(oracle[j]) for j in skeleton.JOINTS if oracle[j]])

    def avg(gs: list[dict[str, Any]], key: str) -> float | None:
        v = [g[key] for g in gs if g[key] is not None]
        return float(np.mean(v)) if v else None

    out["gain_summary"] = {
        "flagged": n_flag, "oracle_flagged": n_oracle, "joint_frames": n_all,
        "mean_pct": avg(gains, "mean_pct"), "sd_pct": avg(gains, "sd_pct"),
        "oracle_mean_pct": avg(o_gains, "mean_pct"), "oracle_sd_pct": avg(o_gains, "sd_pct"),
        "pooled": {"before": _stats(allb), "after": _stats(alla), "oracle_after": _stats(allo),
                   "gain": _gain(allb, alla), "oracle_gain": _gain(allb, allo)},
        "paper_pct": PAPER_GAIN_PCT,
    }  # fmt: skip
    return out


# ----------------------------------------------------------------------------------------------- report


def print_report(res: dict[str, Any]) -> None:
    print("\n### Pairs and alignment (Kinect 30 Hz, Vicon 60 Hz assumed; lag: Vicon time = Kinect time + lag)\n")
    print(
        "| pair | frames K / V | lag s (xcorr r) | lag 1st / 2nd half s | rotation ° | reg. RMS mm | well-estimated "
        "| raw → offline median / RMSE mm |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for p in res["pairs"]:
        print(f"| {p['name']} | {p['kinect_frames']} / {p['vicon_frames']} | {p['lag_s']:+.3f} ({p['xcorr']:.2f}) | "
              f"{p['lag_halves_s'][0]:+.3f} / {p['lag_halves_s'][1]:+.3f} | {p['rotation_deg']:.1f} | "
              f"{p['registration_rms_mm']:.1f} | {', '.join(p['well_estimated'])} | "
              f"{cell(p['median_mm']['raw'])} → {cell(p['median_mm'].get('pipeline_offline'))} / "
              f"{cell(p['rmse_mm']['raw'])} → {cell(p['rmse_mm'].get('pipeline_offline'))} |")  # fmt: skip
    print("\n### Methods against Vicon, pooled over the well-estimated joint-frames\n")
    print(
        "| method | offset mean mm | offset SD mm | median mm | RMSE mm | arm RMSE mm | seg SD mm (arm) | elbow RMSE ° "
        "| s |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for name, m in res["methods"].items():
        print(f"| {name} | {cell(m['mean_mm'])} | {cell(m['sd_mm'])} | {cell(m['median_mm'])} | {cell(m['rmse_mm'])} | "
              f"{cell(m['arm']['rmse_mm'])} | "
              f"{cell(m['segment_sd_mm'])} ({cell(m['arm_segment_sd_mm'])}) | {cell(m['elbow_rmse_deg'], 2)} | "
              f"{cell(m['seconds'], 2)} |")  # fmt: skip
    print("\n### Per joint: offset mean / SD mm (raw, pipeline offline, pipeline online); * = rough Vicon estimate\n")
    shown = [n for n in ("raw", "butterworth", "pipeline_offline", "pipeline_online") if n in res["per_joint"]]
    print("| joint | " + " | ".join(shown) + " | RMSE raw → offline |")
    print("|---" * (len(shown) + 2) + "|")
    for jn in skeleton.JOINTS:
        cells = [res["per_joint"][n][jn] for n in shown]
        mark = "" if cells[0]["well"] else "*"
        row = " | ".join(f"{cell(c['mean_mm'])} / {cell(c['sd_mm'])}" for c in cells)
        off = res["per_joint"].get("pipeline_offline", res["per_joint"]["raw"])[jn]
        print(f"| {jn}{mark} | {row} | {cell(cells[0]['rmse_mm'])} → {cell(off['rmse_mm'])} |")
    g = res["gain_summary"]
    print("\n### Outlier-removal gain (raw offsets, well-estimated joints; paper: mean −2…−8 %, SD −23…−49 %)\n")
    print(f"pipeline flags {g['flagged']} of {g['joint_frames']} joint-frames: gain mean {cell(g['mean_pct'])} %, "
          f"SD {cell(g['sd_pct'])} % (averaged over joints); pooled: mean {cell(g['pooled']['before']['mean_mm'])} → "
          f"{cell(g['pooled']['after']['mean_mm'])} mm, SD {cell(g['pooled']['before']['sd_mm'])} → "
          f"{cell(g['pooled']['after']['sd_mm'])} mm")  # fmt: skip
    print(f"oracle (mixture fitted to the offsets against Vicon, the paper's setting) flags {g['oracle_flagged']}: "
          f"gain mean {cell(g['oracle_mean_pct'])} %, SD {cell(g['oracle_sd_pct'])} %; pooled: mean "
          f"{cell(g['pooled']['oracle_after']['mean_mm'])} mm, "
          f"SD {cell(g['pooled']['oracle_after']['sd_mm'])} mm")  # fmt: skip


def run(paths: list[Path] | None = None, methods: tuple[str, ...] = METHODS,
        config: PipelineConfig | None = None) -> dict[str, Any]:  # fmt: skip
    """Runs the benchmark on the KERAAL pairs (pipeline settings `config`, default PipelineConfig()); returns
    JSON-ready results."""
    config = config or PipelineConfig()
    paths = pair_paths() if paths is None else paths
    if not paths:
        raise FileNotFoundError(f"no KERAAL Kinect/Vicon pairs in {PAIRS_DIR}")
    pairs = [evaluate_pair(*read_pair(p), methods=methods, config=config) for p in paths]
    res = summarise(pairs, methods, config)
    res.update(rate_hz=RATE_HZ, vicon_rate_hz=VICON_RATE_HZ, trim=TRIM, max_lag_s=MAX_LAG_S)
    return res


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", help="also write the results to this file")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="pipeline setting (PipelineConfig), e.g. outlier_excursions=true; repeatable")  # fmt: skip
    args = parser.parse_args(argv)
    try:
        config = pipeline_config(args.set)
    except ValueError as exc:
        parser.error(str(exc))
    started = time.perf_counter()
    res = run(config=config)
    print_report(res)
    print(f"\n({time.perf_counter() - started:.0f} s)")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(res, f, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
