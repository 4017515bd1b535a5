"""The offline smoother against its own online filter, per joint (issue 24, point 2).

A smoother that sees the future should never lose to its causal pass. On short clips of every source with a truth
(HDM05 clips of actors bd and bk per motion class, CMU 13_29 actions, the simulator's exercises), measured by the
project's Kinect model (kinect_agent.sources.kinect_noise) or by white noise, at each view and seed, this prints
per joint the position RMSE of the pipeline offline (process()) and online (the live filter), and every (motion,
view, seed, joint) where offline > online, with the margin.

    python bench/offline_vs_online.py [--views 0 60] [--seeds 1 2 3] [--white 0.02] [--motions rotateArms squat]
                                      [--set NAME=VALUE ...]
"""

from __future__ import annotations

import argparse
import ast
import sys
from pathlib import Path

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:  # `python bench/offline_vs_online.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT_DIR))

from bench.accuracy import run_method  # noqa: E402
from bench.arms import MOTIONS, measure, truths  # noqa: E402
from kinect_agent import skeleton  # noqa: E402
from kinect_agent.processing.config import PipelineConfig  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402
from kinect_agent.sources.simulator import EXERCISES, simulate  # noqa: E402

SIM_REPS = 3


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
    for k, truth in enumerate(truths([motion], 2)):
        measured, true, _ = measure(truth, k, view, seed, white_m=white)
        out.append((measured, true))
    return out


def per_joint(motion: str, view: int, seed: int, white: float | None, config: PipelineConfig) -> dict[str, np.ndarray]:
    """Returns {"pipeline_offline", "pipeline_online": (J,) RMSE mm} pooled over the motion's clips."""
    sums: dict[str, list[np.ndarray]] = {"pipeline_offline": [], "pipeline_online": []}
    for measured, true in _clips(motion, view, seed, white):
        for method in sums:
            est, _ = run_method(method, measured, config)
            sums[method].append(np.sum((est - true) ** 2, axis=-1))
    return {m: 1000.0 * np.sqrt(np.mean(np.concatenate(v, axis=0), axis=0)) for m, v in sums.items()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--views", type=int, nargs="+", default=[0, 60])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--white", type=float, help="white noise of this SD per axis, m, instead of the Kinect model")
    parser.add_argument("--motions", nargs="+", default=[*MOTIONS, *(f"sim_{e}" for e in EXERCISES)])
    parser.add_argument("--set", nargs="*", default=[], help="PipelineConfig overrides NAME=VALUE")
    args = parser.parse_args(argv)
    config = PipelineConfig(**{k: ast.literal_eval(v) for k, v in (s.split("=", 1) for s in args.set)})
    noise = f"white {args.white * 1000:.0f} mm" if args.white else "Kinect 2 model"
    print(f"offline vs online per joint, {noise}, overrides {args.set or 'none'}")
    losses, rows = [], 0
    for motion in args.motions:
        for view in args.views:
            for seed in args.seeds:
                r = per_joint(motion, view, seed, args.white, config)
                off, on = r["pipeline_offline"], r["pipeline_online"]
                rows += 1
                worse = [(skeleton.JOINTS[j], off[j], on[j]) for j in np.flatnonzero(off > on)]
                losses += [(motion, view, seed, *w) for w in worse]
                lost = ", ".join(f"{j} {a:.1f}>{b:.1f}" for j, a, b in worse) or "none"
                print(
                    f"  {motion:22s} {view:3d}° seed {seed}: all joints offline {np.sqrt(np.mean(off**2)):6.1f} "
                    f"online {np.sqrt(np.mean(on**2)):6.1f} mm; offline loses at: {lost}",
                    flush=True,
                )
    print(f"{rows} rows (motion, view, seed), {len(losses)} (row, joint) pairs where offline > online")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
