"""The offline smoother against its own online filter, per joint (issue 24, point 2).

A smoother that sees the future should never lose to its causal pass. On short clips of every source with a truth
(HDM05 clips of actors bd and bk per motion class, CMU 13_29 actions, the simulator's exercises), measured by the
project's Kinect model (kinect_agent.sources.kinect_noise) or by white noise, at each view and seed, this prints
per joint the position RMSE of the pipeline offline (process()) and online (the live filter), and every (motion,
view, seed, joint) where offline > online + tolerance, with the margin.

The property it reports: "offline ≤ online + tolerance at every joint of every (motion, view, seed) row". At the end:
rows measured, rows losing somewhere, (row, joint) pairs lost, the worst joint margin (offline − online, mm, and
where), per source (hdm05, cmu, sim), and with --markdown one line per motion with a cell per (view, seed):
"joints lost / worst margin mm" (the tables of bench/README.md). The online filter always runs with the shipped
defaults (the property is about the offline pass: --set changes the offline settings only, unless --set-online).
With --forward the same report compares, instead, the offline pipeline's unscented RTS output with the forward pass 3
it smooths (same lengths, same noise model): whether the smoother itself is never worse than its causal pass
("offline" columns = RTS, "online" = pass 3).

    python bench/offline_vs_online.py [--views 0 60] [--seeds 1 2 3] [--white 0.02] [--motions rotateArms squat]
                                      [--tolerance-mm 1] [--set NAME=VALUE ...] [--set-online NAME=VALUE ...]
                                      [--forward] [--markdown] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:  # `python bench/offline_vs_online.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT_DIR))

from bench.accuracy import pipeline_config, run_method  # noqa: E402
from bench.arms import MOTIONS, measure, truths  # noqa: E402
from kinect_agent import skeleton  # noqa: E402
from kinect_agent.blas_threads import one_blas_thread  # noqa: E402
from kinect_agent.processing.combined_outliers import remove_outliers_combined  # noqa: E402
from kinect_agent.processing.config import PipelineConfig  # noqa: E402
from kinect_agent.processing.ik import inverse_kinematics  # noqa: E402
from kinect_agent.processing.pipeline import smooth  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402
from kinect_agent.sources.simulator import EXERCISES, simulate  # noqa: E402

SIM_REPS = 3


def source_of(motion: str) -> str:
    """Returns the source of a motion name: "sim" (sim_ + a simulator exercise), "cmu" (cmu_ + a 13_29 action) or
    "hdm05"."""
    return "sim" if motion.startswith("sim_") else "cmu" if motion.startswith("cmu_") else "hdm05"


def _clips(motion: str, view: int, seed: int, white: float | None) -> list[tuple[Recording, np.ndarray]]:
    """Returns [(measured, truth (T, J, 3) m)] of one motion (an HDM05/CMU name of bench.arms, or sim_ and a
    simulator exercise) at one view and seed."""
    if motion.startswith("sim_"):
        measured, truth, _ = simulate(motion.removeprefix("sim_"), SIM_REPS, view_deg=view, seed=seed)
        if white is not None:
            rng = np.random.default_rng([seed, view, 7])
            noisy = truth.positions + white * rng.standard_normal(truth.positions.shape)
            measured = truth.replace(step=f"white noise {white} m", positions=noisy)
        return [(measured, truth.positions)]
    out = []
    for k, clip in enumerate(truths([motion], 2)):
        measured, true, _ = measure(clip, k, view, seed, white_m=white)
        out.append((measured, true))
    return out


@dataclass
class Row:
    """One (motion, view, seed): per-joint position RMSE (J,) mm of the offline and the online pipeline."""

    motion: str
    view: int
    seed: int
    offline_mm: np.ndarray
    online_mm: np.ndarray

    def margins(self) -> np.ndarray:
        """Returns (J,) offline − online RMSE, mm (> 0: offline loses at that joint)."""
        return self.offline_mm - self.online_mm

    def lost(self, tolerance_mm: float) -> np.ndarray:
        """Returns the indices of the joints where offline > online + tolerance_mm."""
        return np.flatnonzero(self.margins() > tolerance_mm)


def smoothed_and_forward(rec: Recording, config: PipelineConfig) -> tuple[np.ndarray, np.ndarray]:
    """Returns (the unscented RTS output, pass 3's forward estimate), both (T, J, 3) m with the same lengths: the
    offline pipeline's outlier step, inverse kinematics and passes (pipeline.smooth), without its rigid-input and
    offset steps."""
    with one_blas_thread():
        clean = remove_outliers_combined(rec, config)[0] if config.remove_outliers else rec
        ik = inverse_kinematics(clean.positions)
        root, lengths, theta, info = smooth(clean, ik, config, forward=True)
    lengths_t = np.broadcast_to(lengths, (clean.n_frames, len(lengths)))
    f_root, f_theta = info["forward"]
    return ik.model.positions(root, lengths_t, theta), ik.model.positions(f_root, lengths_t, f_theta)


def per_joint(
    motion: str,
    view: int,
    seed: int,
    white: float | None,
    config: PipelineConfig,
    online_config: PipelineConfig,
    forward: bool = False,
) -> Row:
    """Returns the Row of one (motion, view, seed), RMSE pooled over the motion's clips; forward=True: the RTS output
    against its own forward pass 3 (smoothed_and_forward) in place of offline against online."""
    sq: dict[str, list[np.ndarray]] = {"offline": [], "online": []}
    for measured, true in _clips(motion, view, seed, white):
        if forward:
            estimates = smoothed_and_forward(measured, config)
        else:
            estimates = (
                run_method("pipeline_offline", measured, config)[0],
                run_method("pipeline_online", measured, online_config)[0],
            )
        for key, est in zip(sq, estimates, strict=True):
            sq[key].append(np.sum((est - true) ** 2, axis=-1))
    rmse = {m: 1000.0 * np.sqrt(np.mean(np.concatenate(v, axis=0), axis=0)) for m, v in sq.items()}
    return Row(motion, view, seed, rmse["offline"], rmse["online"])


def summary(rows: list[Row], tolerance_mm: float, labels: tuple[str, str] = ("offline", "online")) -> str:
    """Returns the property's summary line of some rows: rows losing, pairs lost, worst margin and where."""
    if not rows:
        return "no rows"
    losing = [r for r in rows if len(r.lost(tolerance_mm))]
    pairs = sum(len(r.lost(tolerance_mm)) for r in rows)
    worst = max(rows, key=lambda r: float(r.margins().max()))
    j = int(np.argmax(worst.margins()))
    return (
        f"{len(losing)} of {len(rows)} rows lose at some joint by > {tolerance_mm:g} mm, {pairs} (row, joint) pairs; "
        f"worst margin {worst.margins()[j]:+.1f} mm ({worst.motion} {worst.view}° seed {worst.seed} "
        f"{skeleton.JOINTS[j]}: {worst.offline_mm[j]:.1f} vs {worst.online_mm[j]:.1f}); all joints {labels[0]} "
        f"{np.mean([np.sqrt(np.mean(r.offline_mm**2)) for r in rows]):.1f} / {labels[1]} "
        f"{np.mean([np.sqrt(np.mean(r.online_mm**2)) for r in rows]):.1f} mm (mean over rows)"
    )


def markdown(rows: list[Row], tolerance_mm: float) -> str:
    """Returns a markdown table: one line per motion, a cell per (view, seed) "joints lost / worst margin mm"."""
    keys = sorted({(r.view, r.seed) for r in rows})
    motions = list(dict.fromkeys(r.motion for r in rows))
    by = {(r.motion, r.view, r.seed): r for r in rows}
    lines = [
        "| motion | " + " | ".join(f"{v}° s{s}" for v, s in keys) + " |",
        "|---|" + "---|" * len(keys),
    ]
    for m in motions:
        cells = []
        for v, s in keys:
            r = by.get((m, v, s))
            cells.append("" if r is None else f"{len(r.lost(tolerance_mm))} / {r.margins().max():+.1f}")
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--views", type=int, nargs="+", default=[0, 60])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--white", type=float, help="white noise of this SD per axis, m, instead of the Kinect model")
    parser.add_argument("--motions", nargs="+", default=[*MOTIONS, *(f"sim_{e}" for e in EXERCISES)])
    parser.add_argument("--tolerance-mm", type=float, default=0.0, help="a joint loses when offline > online + this")
    parser.add_argument("--set", nargs="*", default=[], help="PipelineConfig overrides of the offline pass")
    parser.add_argument("--set-online", nargs="*", default=[], help="PipelineConfig overrides of the online filter")
    parser.add_argument("--forward", action="store_true", help="the RTS output against its forward pass 3 instead")
    parser.add_argument("--markdown", action="store_true", help="also print the per-motion table")
    parser.add_argument("--json", type=Path, help="also write every row's per-joint RMSE to this file")
    args = parser.parse_args(argv)
    config, online_config = pipeline_config(args.set), pipeline_config(args.set_online)
    noise = f"white {args.white * 1000:.0f} mm" if args.white else "Kinect 2 model"
    overrides = f"offline overrides {args.set or 'none'}, online {args.set_online or 'none'}"
    labels = ("RTS", "forward") if args.forward else ("offline", "online")
    pair = "RTS output vs its forward pass 3" if args.forward else "offline vs online"
    print(f"{pair} per joint, {noise}, {overrides}")
    rows: list[Row] = []
    for motion in args.motions:
        for view in args.views:
            for seed in args.seeds:
                r = per_joint(motion, view, seed, args.white, config, online_config, args.forward)
                rows.append(r)
                lost = ", ".join(
                    f"{skeleton.JOINTS[j]} {r.offline_mm[j]:.1f}>{r.online_mm[j]:.1f}"
                    for j in r.lost(args.tolerance_mm)
                )
                off, on = np.sqrt(np.mean(r.offline_mm**2)), np.sqrt(np.mean(r.online_mm**2))
                print(
                    f"  {motion:22s} {view:3d}° seed {seed}: all joints {labels[0]} {off:6.1f} {labels[1]} "
                    f"{on:6.1f} mm; worst margin {r.margins().max():+5.1f} mm; "
                    f"{labels[0]} loses at: {lost or 'none'}",
                    flush=True,
                )
    print(f"all: {summary(rows, args.tolerance_mm, labels)}")
    for source in ("hdm05", "cmu", "sim"):
        part = [r for r in rows if source_of(r.motion) == source]
        if part:
            print(f"{source}: {summary(part, args.tolerance_mm, labels)}")
    if args.markdown:
        print(markdown(rows, args.tolerance_mm))
    if args.json:
        doc = [
            {"motion": r.motion, "view": r.view, "seed": r.seed, "joints": list(skeleton.JOINTS),
             "offline_mm": r.offline_mm.round(2).tolist(), "online_mm": r.online_mm.round(2).tolist()}
            for r in rows
        ]  # fmt: skip
        args.json.write_text(json.dumps({"noise": noise, "offline": args.set, "online": args.set_online, "rows": doc}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
