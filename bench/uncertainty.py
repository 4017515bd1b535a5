"""Calibration of the angle SDs and of the 95 % metric intervals on simulated sessions with known truth (issue 13).

    .venv/bin/python bench/uncertainty.py [--reps 5] [--json out.json]

Training set (fit): every simulated exercise at views 0° and 60°, seeds 101-103. Held-out set (validation): every
exercise at views 0° and 30°, seeds 201-203 (another view, other seeds; the motions are shared because each
exercise is the only one that moves some angles, and an angle's bias depends on how it moves). Prints
  1. the per-frame inflation: SD of (angle error − its session mean) / the model SD, per angle (median = the
     INFLATION of kinect_agent.processing.uncertainty);
  2. the systematic part b per angle and kind (level: peak/min, range), fitted on the training set so that 95 % of
     its intervals cover the truth (the SYSTEMATIC_DEG of backend.analysis.intervals);
  3. the coverage of the shipped intervals on both sets, per (motion, view) family and pooled;
  4. the cost of the per-frame SDs on 10 minutes at 30 Hz.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import dataclass

import numpy as np

from backend.analysis import intervals
from backend.analysis.range_of_motion import range_of_motion
from kinect_agent.analysis import series
from kinect_agent.processing import uncertainty
from kinect_agent.processing.angles import ANGLE_NAMES, joint_angles
from kinect_agent.processing.pipeline import process
from kinect_agent.sources.simulator import EXERCISES, simulate

MOTIONS = EXERCISES
TRAIN_VIEWS, TRAIN_SEEDS = (0, 60), (101, 102, 103)
TEST_VIEWS, TEST_SEEDS = (0, 30), (201, 202, 203)
KINDS = ("min_deg", "max_deg", "range_deg")


@dataclass
class Case:
    """One simulated session: angles of the filtered and of the true positions (degrees), the shipped SDs."""

    motion: str
    view: int
    seed: int
    t: np.ndarray
    est: dict[str, np.ndarray]
    truth: dict[str, np.ndarray]
    sd: dict[str, np.ndarray]


def simulate_case(motion: str, view: int, seed: int, reps: int) -> Case:
    """Returns one case: simulate, run the pipeline, measure angles as the server does (smoothed positions)."""
    measured, truth, _ = simulate(motion, reps, view_deg=view, seed=seed)
    result = process(measured)
    est = joint_angles(series.smooth_positions(measured.t, result.filtered.positions))
    true = joint_angles(series.smooth_positions(truth.t, truth.positions))
    return Case(motion, view, seed, measured.t, est, true, result.angle_sd)


def collect(motions: tuple[str, ...], views: tuple[int, ...], seeds: tuple[int, ...], reps: int) -> list[Case]:
    """Returns the cases of every motion × view × seed."""
    return [simulate_case(m, v, s, reps) for m in motions for v in views for s in seeds]


def frame_inflation(cases: list[Case]) -> dict[str, float]:
    """Returns {angle: SD of (error − session mean error) / model SD}, pooled over the cases."""
    out: dict[str, float] = {}
    for name in ANGLE_NAMES:
        z = []
        for c in cases:
            e = (c.est[name] - c.truth[name] + 180.0) % 360.0 - 180.0
            model = c.sd[name] / uncertainty.INFLATION
            ok = np.isfinite(e) & np.isfinite(model)
            if ok.sum() > 2:
                z.append((e[ok] - np.mean(e[ok])) / model[ok])
        out[name] = float(np.std(np.concatenate(z))) if z else float("nan")
    return out


def metric_errors(case: Case, name: str) -> dict[str, tuple[float, float, float]] | None:
    """Returns {kind: (estimate, truth, σ_frames)} of one angle, or None when either series is unusable."""
    e = intervals.edges(case.t, case.est[name], case.sd[name])
    true = range_of_motion(case.t, {name: case.truth[name]}, presmoothed=True)[name]
    iv = intervals.angle_intervals(case.t, case.est[name], case.sd[name], name)
    if e is None or iv is None or true["range_deg"] is None or true["range_deg"] >= intervals.MAX_RANGE_DEG:
        return None
    return {
        "min_deg": (e.low, true["min_deg"], e.sd_low),
        "max_deg": (e.high, true["max_deg"], e.sd_high),
        "range_deg": (e.high - e.low, true["range_deg"], float(np.hypot(e.sd_low, e.sd_high))),
    }


def _error(est: float, true: float, kind: str) -> float:
    """Returns est − true in degrees; for an end of the range (an angle) taken modulo a turn, within ±180°."""
    d = est - true
    return d if kind == "range_deg" else (d + 180.0) % 360.0 - 180.0


def _pair(name: str) -> str:
    """Returns the angle's name without its side (elbow_flexion_L -> elbow_flexion)."""
    return name[:-2] if name[-2:] in ("_L", "_R") else name


def fit_systematic(cases: list[Case], coverage: float = 0.95) -> dict[str, tuple[float, float, float]]:
    """Returns {angle: (b_min, b_max, b_range)} degrees: per kind, the smallest b covering `coverage` of the
    training intervals of that angle, both sides pooled (the body and the errors are left-right symmetric)."""
    need: dict[str, dict[str, list[float]]] = {}
    for name in ANGLE_NAMES:
        for c in cases:
            errs = metric_errors(c, name)
            if errs is None:
                continue
            for kind, (est, true, sigma) in errs.items():
                b2 = (_error(est, true, kind) / intervals.Z95) ** 2 - sigma**2
                need.setdefault(_pair(name), {}).setdefault(kind, []).append(float(np.sqrt(max(b2, 0.0))))
    out = {}
    for name in ANGLE_NAMES:
        per = need.get(_pair(name))
        if per:
            fit = [round(float(np.quantile(per[k], coverage)), 1) for k in KINDS]
            out[name] = (fit[0], fit[1], fit[2])
    return out


def coverage_table(cases: list[Case]) -> dict[str, dict[str, float]]:
    """Returns {family "motion@view" and "pooled": {kind: fraction of 95 % intervals that hold the truth, "n"}}."""
    hits: dict[str, dict[str, list[bool]]] = {}
    for c in cases:
        fam = f"{c.motion}@{c.view}"
        for name in ANGLE_NAMES:
            iv = intervals.angle_intervals(c.t, c.est[name], c.sd[name], name)
            true = range_of_motion(c.t, {name: c.truth[name]}, presmoothed=True)[name]
            if iv is None or true["range_deg"] is None or true["range_deg"] >= intervals.MAX_RANGE_DEG:
                continue
            for kind in KINDS:
                ok = intervals.covers(iv[kind], true[kind], kind)
                for key in (fam, "pooled"):
                    hits.setdefault(key, {}).setdefault(kind, []).append(ok)
    table = {}
    for key, per in hits.items():
        row = {kind: round(float(np.mean(v)), 3) for kind, v in per.items()}
        row["all"] = round(float(np.mean(sum(per.values(), []))), 3)
        row["n"] = len(sum(per.values(), []))
        table[key] = row
    return table


def cost_seconds(minutes: float = 10.0) -> dict[str, float]:
    """Returns the pipeline's and the SD step's seconds on a simulated recording of about `minutes` at 30 Hz."""
    warm, _, _ = simulate("squat", 2, seed=1)
    process(warm)
    measured, _, _ = simulate("squat", int(round(minutes * 13)), seed=1)
    started = time.perf_counter()
    result = process(measured)
    return {
        "frames": measured.n_frames,
        "pipeline_s": round(time.perf_counter() - started, 2),
        "angle_sd_s": result.quality["angle_sd_seconds"],
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--json")
    parser.add_argument("--no-cost", action="store_true")
    args = parser.parse_args(argv)
    train = collect(MOTIONS, TRAIN_VIEWS, TRAIN_SEEDS, args.reps)
    test = collect(MOTIONS, TEST_VIEWS, TEST_SEEDS, args.reps)
    inflation = frame_inflation(train)
    print("per-frame inflation (train), SD of detrended error / model SD:")
    for name, v in inflation.items():
        print(f"  {name:24s} {v:6.2f}")
    print(f"  median {np.nanmedian(list(inflation.values())):.2f} (shipped INFLATION = {uncertainty.INFLATION})")
    fitted = fit_systematic(train)
    print("systematic part b fitted on train (min_deg, max_deg, range_deg), degrees:")
    for name, b in fitted.items():
        print(f"  {name:24s} {b}   shipped {intervals.SYSTEMATIC_DEG.get(name)}")
    report = {"inflation": inflation, "fitted_systematic": fitted}
    for label, cases in (("train", train), ("held-out", test)):
        table = coverage_table(cases)
        report[label] = table
        print(f"coverage of the shipped 95 % intervals, {label}:")
        for key, row in table.items():
            print(f"  {key:32s} " + "  ".join(f"{k} {v}" for k, v in row.items()))
    if not args.no_cost:
        report["cost"] = cost_seconds()
        print("cost, 10 min at 30 Hz:", report["cost"])
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(report, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
