"""The Kinect's segment-length bias against simultaneous mocap, and the length-bias step's validation (issue 24.3).

Data (the only simultaneous Kinect v2 + mocap in ../shared/data; one subject per dataset, so no leave-one-subject-out
inside a dataset: UI-PRMD's Vicon is s01 only, s02-s05 are Kinect alone):
    KERAAL   group 3, subject P1: 3 trials (CTK, ELK, RTK); Vicon joints by SCoRE; a segment is scored in a trial
             when both its ends are well estimated there (evaluation.pairs.well_estimated).
    UI-PRMD  subject s01: movements m01-m10, episodes e01-e10, correct and incorrect (200 episodes); Vicon joints are
             Plug-in Gait skin markers (acromion, lateral epicondyle, wrist bar middle), formats.ui_prmd_vicon.
Segments modelled: the four arm segments (ARM_UP_L/R: SHO-ELB, ARM_LO_L/R: ELB-WRI), the only ones both datasets'
mocap estimates (KERAAL's legs fall back in every trial, UI-PRMD's Kinect legs move with the pelvis, HAND/FOOT ends
are skin targets, PELVIC's ROOT is defined differently by the two mocap sets).
Lengths need no time alignment: per trial, the median over frames of the mocap segment length, of the raw Kinect
one, and the segment length the pipeline fixes (quality["segment_lengths_m"]) under the settings compared.
Ratio of a trial and segment: mocap / filter. Model: per segment, the median of the training trials' ratios.
Validation of the lengths (mean |error| mm over test trials and segments): KERAAL leave-one-trial-out, UI-PRMD
leave-one-movement-out (its 20 episodes, correct and incorrect), fit on one dataset and test on the other.
Positions (--positions): KERAAL through bench/real_pairs.py, UI-PRMD s01 through the aligned episode pairs that
bench/offset_model.py accepts (offline and online RMSE per joint, registered per estimate), each with the ratios
fitted on the other dataset (cross-dataset) and on all (in-sample).

    .venv/bin/python bench/length_bias.py [--settings default ub] [--positions] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:
    sys.path.insert(0, str(ROOT_DIR))

from bench import offset_model as om  # noqa: E402
from bench import real_pairs as rp  # noqa: E402
from kinect_agent import skeleton  # noqa: E402
from kinect_agent.evaluation.pairs import joint_mask, well_estimated  # noqa: E402
from kinect_agent.processing import length_bias  # noqa: E402
from kinect_agent.processing.config import PipelineConfig  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402

SEGMENTS = ("ARM_UP_L", "ARM_LO_L", "ARM_UP_R", "ARM_LO_R")
SETTINGS: dict[str, dict[str, Any]] = {
    "default": {},
    # the unbiased filter: innovation at the mean state in every pass, a 0.3-s outlier window (issue 24 point 2)
    "ub": {"innovation_at_mean": True, "outlier_window_s": 0.3},
    # unbiased lengths only (passes 1-2), pass 3 as shipped
    "lw": {"innovation_at_mean": True, "fixed_innovation_at_mean": False, "outlier_window_s": 0.3},
}


def _median_segments(positions: np.ndarray) -> np.ndarray:
    """Returns (len(SEGMENTS),) m: the median over frames of each modelled segment's length; NaN if never seen."""
    seg = skeleton.segment_lengths(positions)[:, [skeleton.SEGMENT_NAMES.index(s) for s in SEGMENTS]]
    ok = np.isfinite(seg).sum(axis=0) > 0
    out = np.full(len(SEGMENTS), np.nan)
    out[ok] = np.nanmedian(seg[:, ok], axis=0)
    return out


def _filter_segments(rec: Recording, config: PipelineConfig) -> np.ndarray:
    """Returns (len(SEGMENTS),) m: the lengths the offline pipeline fixes for the modelled segments."""
    lengths = process(rec, config=config).quality["segment_lengths_m"]
    return np.array([lengths["-".join(skeleton.SEGMENTS[s])] for s in SEGMENTS])


def trials(settings: list[str]) -> list[dict[str, Any]]:
    """Returns one entry per trial: dataset, group (the unit held out), name, mocap / raw (len(SEGMENTS),) m (NaN
    where not scored) and filter {setting: (len(SEGMENTS),) m}."""
    from kinect_agent.formats import ui_prmd, ui_prmd_vicon

    out: list[dict[str, Any]] = []
    for path in rp.pair_paths():
        kinect, vicon = rp.read_pair(path)
        good = well_estimated(vicon.meta.extra.get("fallback_joints", []))
        scored = np.array([good[skeleton.INDEX[a]] and good[skeleton.INDEX[b]] for a, b in
                           (skeleton.SEGMENTS[s] for s in SEGMENTS)])  # fmt: skip
        mocap = np.where(scored, _median_segments(vicon.positions), np.nan)
        name = kinect.meta.exercise or path.stem
        out.append({"dataset": "KERAAL", "group": name, "name": name, "kinect": kinect, "mocap": mocap})
    for folder, suffix in om.UI_FOLDERS:
        for m in range(1, 11):
            for e in range(1, 11):
                fname = f"m{m:02d}_s01_e{e:02d}_positions{suffix}.txt.gz"
                k_path, v_path = (om.UI_DIR / folder / dev / "Positions" / fname for dev in ("Kinect", "Vicon"))
                if not (k_path.is_file() and v_path.is_file()):
                    continue
                kinect = ui_prmd.read(k_path)
                mocap = _median_segments(ui_prmd_vicon.read(v_path).positions)
                out.append({"dataset": "UI-PRMD", "group": f"m{m:02d}", "name": f"m{m:02d}_e{e:02d}{suffix}",
                            "kinect": kinect, "mocap": mocap})  # fmt: skip
    for tr in out:
        tr["raw"] = _median_segments(tr["kinect"].positions)
        tr["filter"] = {s: _filter_segments(tr["kinect"], PipelineConfig(**SETTINGS[s])) for s in settings}
    return out


def fit(train: list[dict[str, Any]], setting: str) -> np.ndarray:
    """Returns (len(SEGMENTS),) the median over training trials of mocap / filter length (1 where none scored)."""
    ratios = np.array([tr["mocap"] / tr["filter"][setting] for tr in train])
    ok = np.isfinite(ratios).sum(axis=0) > 0
    out = np.ones(len(SEGMENTS))
    out[ok] = np.nanmedian(ratios[:, ok], axis=0)
    return out


def length_errors(test: list[dict[str, Any]], setting: str, ratio: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Returns (before, after): (n, len(SEGMENTS)) mm, filter length (times ratio) minus mocap."""
    est = np.array([tr["filter"][setting] for tr in test])
    mocap = np.array([tr["mocap"] for tr in test])
    return 1e3 * (est - mocap), 1e3 * (est * ratio - mocap)


def schemes(all_trials: list[dict[str, Any]]) -> dict[str, list[tuple[list[dict[str, Any]], list[dict[str, Any]]]]]:
    """Returns {scheme: [(train, test), ...]}: leave one group out per dataset, cross-dataset both ways, in-sample."""
    by = {d: [t for t in all_trials if t["dataset"] == d] for d in ("KERAAL", "UI-PRMD")}
    out: dict[str, list[tuple[list[dict[str, Any]], list[dict[str, Any]]]]] = {}
    for d, ts in by.items():
        groups = sorted({t["group"] for t in ts})
        out[f"{d} leave one {'trial' if d == 'KERAAL' else 'movement'} out"] = [
            ([t for t in ts if t["group"] != g], [t for t in ts if t["group"] == g]) for g in groups
        ]
        out[f"{d} in-sample"] = [(ts, ts)]
    out["fit UI-PRMD, test KERAAL"] = [(by["UI-PRMD"], by["KERAAL"])]
    out["fit KERAAL, test UI-PRMD"] = [(by["KERAAL"], by["UI-PRMD"])]
    return out


def validate(all_trials: list[dict[str, Any]], setting: str) -> dict[str, Any]:
    """Returns {scheme: {before, after: mean |error| mm per segment and pooled}}."""
    res = {}
    for name, folds in schemes(all_trials).items():
        b, a = [], []
        for train, test in folds:
            before, after = length_errors(test, setting, fit(train, setting))
            b.append(before)
            a.append(after)
        before, after = np.concatenate(b), np.concatenate(a)
        res[name] = {
            "before_mm": [float(v) for v in np.nanmean(np.abs(before), axis=0)],
            "after_mm": [float(v) for v in np.nanmean(np.abs(after), axis=0)],
            "pooled_mm": [float(np.nanmean(np.abs(before))), float(np.nanmean(np.abs(after)))],
        }
    return res


def table(all_trials: list[dict[str, Any]], settings: list[str]) -> dict[str, Any]:
    """Returns per dataset (and UI-PRMD movement): median mocap, raw, filter lengths (mm) and ratios per segment."""
    out: dict[str, Any] = {}
    keys = [("KERAAL", None)] + [("UI-PRMD", None)] + [("UI-PRMD", f"m{m:02d}") for m in range(1, 11)]
    for d, g in keys:
        ts = [t for t in all_trials if t["dataset"] == d and (g is None or t["group"] == g)]
        if not ts:
            continue
        row: dict[str, Any] = {"n": len(ts)}
        for key in ("mocap", "raw"):
            row[key] = [float(v) for v in 1e3 * np.nanmedian([t[key] for t in ts], axis=0)]
        for s in settings:
            row[s] = [float(v) for v in 1e3 * np.nanmedian([t["filter"][s] for t in ts], axis=0)]
            row[f"ratio_{s}"] = [float(v) for v in fit(ts, s)]
        out[d if g is None else f"{d} {g}"] = row
    return out


def ui_pairs() -> list[om.Pair]:
    """UI-PRMD s01 episode pairs accepted by offset_model's alignment rule."""
    return [p for p in om.uiprmd_pairs(range(1, 11)) if p.accepted]


def ui_positions(pairs: list[om.Pair], config: PipelineConfig) -> dict[str, Any]:
    """Returns offline and online RMSE mm per scored joint and pooled, over the accepted UI-PRMD pairs."""
    joints = joint_mask(om.UI_JOINTS)
    sq: dict[str, list[np.ndarray]] = {"offline": [], "online": []}
    for pair in pairs:
        for method in sq:
            est = process(pair.kinect, online=method == "online", config=config).filtered.positions
            truth = om.register(est, pair.vicon, pair.joints)
            sq[method].append(np.sum((est - truth) ** 2, axis=-1)[:, joints])
    out: dict[str, Any] = {}
    for method, parts in sq.items():
        s = np.concatenate(parts)
        out[method] = {
            "pooled_mm": float(1e3 * np.sqrt(np.nanmean(s))),
            "per_joint_mm": {
                j: float(1e3 * np.sqrt(np.nanmean(s[:, k]))) for k, j in enumerate(om.UI_JOINTS)
            },  # fmt: skip
            "per_movement_mm": {},
        }
        for g in sorted({p.group for p in pairs}):
            sg = np.concatenate([v for v, p in zip(parts, pairs, strict=True) if p.group == g])
            out[method]["per_movement_mm"][g] = {
                "n": sum(p.group == g for p in pairs),
                "pooled": float(1e3 * np.sqrt(np.nanmean(sg))),
                "per_joint": [float(1e3 * np.sqrt(np.nanmean(sg[:, k]))) for k in range(sg.shape[1])],
            }
    return out


def keraal_positions(config: PipelineConfig) -> dict[str, Any]:
    """Returns real_pairs' pooled RMSE / elbow RMSE and per-joint RMSE of the pipeline offline and online."""
    res = rp.run(methods=("pipeline_offline", "pipeline_online"), config=config)
    return res


def ratios_dict(ratio: np.ndarray, segments: list[str]) -> dict[str, float]:
    """Returns the step's table (PipelineConfig.length_bias) of the modelled `segments` (others left at 1)."""
    return {s: round(float(r), 4) for s, r in zip(SEGMENTS, ratio, strict=True) if s in segments}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--settings", nargs="+", default=["default", "ub"], choices=list(SETTINGS))
    parser.add_argument("--positions", action="store_true", help="also position RMSE with the step on (slow)")
    parser.add_argument(
        "--fits",
        nargs="+",
        default=["none", "UI-PRMD", "KERAAL"],
        choices=["none", "UI-PRMD", "KERAAL", "both", "table"],
        help="--positions: where the ratios come from",
    )
    parser.add_argument(
        "--model-segments",
        nargs="+",
        default=list(SEGMENTS),
        choices=list(SEGMENTS),
        help="--positions: the segments the step scales (the others keep factor 1)",
    )
    parser.add_argument("--json", help="write the results here")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    all_trials = trials(args.settings)
    res: dict[str, Any] = {"segments": list(SEGMENTS), "table": table(all_trials, args.settings), "validation": {}}
    for s in args.settings:
        res["validation"][s] = validate(all_trials, s)
    print(f"segments {SEGMENTS}; lengths mm (median over trials), ratio = mocap / filter")
    for key, row in res["table"].items():
        print(
            f"  {key} [{row['n']}]: mocap {np.round(row['mocap'])} raw {np.round(row['raw'])} "
            + " ".join(f"{s} {np.round(row[s])} ratio {np.round(row[f'ratio_{s}'], 3)}" for s in args.settings)
        )
    for s, v in res["validation"].items():
        print(f"validation, setting {s}: mean |length error| mm per segment before -> after (pooled)")
        for name, r in v.items():
            print(
                f"  {name}: {np.round(r['before_mm'], 1)} -> {np.round(r['after_mm'], 1)} "
                f"({r['pooled_mm'][0]:.1f} -> {r['pooled_mm'][1]:.1f})"
            )
    if args.positions:
        by = {d: [t for t in all_trials if t["dataset"] == d] for d in ("KERAAL", "UI-PRMD")}
        pairs = ui_pairs()
        res["positions"] = {}
        for s in args.settings:
            fits = {"none": None, "UI-PRMD": fit(by["UI-PRMD"], s), "KERAAL": fit(by["KERAAL"], s),
                    "both": fit(all_trials, s), "table": None}  # fmt: skip
            for fname in args.fits:
                ratio = fits[fname]
                bias = None if ratio is None else ratios_dict(ratio, args.model_segments)
                if fname == "table":  # the shipped Kinect 2 table (length_bias.RATIOS), fitted on both
                    bias = length_bias.RATIOS["kinect2"]
                config = PipelineConfig(**SETTINGS[s], length_bias=bias)
                k = keraal_positions(config)
                u = ui_positions(pairs, config)
                res["positions"][f"{s} / fit {fname}"] = {"ratios": bias, "keraal": k, "uiprmd": u}
                off, onl = k["methods"]["pipeline_offline"], k["methods"]["pipeline_online"]
                print(f"positions {s}, ratios fitted on {fname} {bias}: KERAAL offline {off['rmse_mm']:.1f} mm elbow "
                      f"{off['elbow_rmse_deg']:.2f} deg (online {onl['rmse_mm']:.1f}, {onl['elbow_rmse_deg']:.2f}); "
                      f"UI-PRMD s01 [{len(pairs)} pairs] offline {u['offline']['pooled_mm']:.1f} online "
                      f"{u['online']['pooled_mm']:.1f} mm", flush=True)  # fmt: skip
    print(f"({time.perf_counter() - started:.0f} s)")
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1, default=str), encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
