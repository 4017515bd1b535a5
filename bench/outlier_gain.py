"""The simulator's tracking-loss law against the paper's outlier-removal gains, per setting (issue 24 decision 4).

For each device, pose and view: one long simulated session (standing squats, or the seated knee extension for the
sitting tables, 30 Hz), kinect_noise.add_kinect_noise, and the gains of removing exactly the simulated outliers (the
oracle), as tests/kinect_agent/sources/test_kinect_noise.py computes them: over TRACKED joint-frames, the mean gain
100·(1 − mean distance kept / mean distance all) pooled over joints, and the SD gain per joint 100·(1 − SD kept /
SD all), averaged over joints. Beside them the paper's table (outlier_removal_gain_pct.csv), the outlier fraction
and the jump lengths of the law (median over joints; before decision 4 the second number of outlier_law was the
excess distance beyond the mean offset, from the truth), and the joints whose fraction is capped.

    python bench/outlier_gain.py [--reps 40] [--seeds 11 12 13]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:
    sys.path.insert(0, str(ROOT_DIR))

from kinect_agent import skeleton  # noqa: E402
from kinect_agent.sources import kinect_noise  # noqa: E402
from kinect_agent.sources.simulator import simulate_truth  # noqa: E402


def gains(measured_d: np.ndarray, tracked: np.ndarray, mask: np.ndarray) -> tuple[float, float]:
    """Returns (mean gain, SD gain) in %: measured_d (T, J) m distance to the truth; tracked, mask (T, J) bool."""
    with_outliers = np.where(tracked, measured_d, np.nan)
    without = np.where(tracked & ~mask, measured_d, np.nan)
    mean_gain = 100 * (1 - np.nanmean(without) / np.nanmean(with_outliers))
    sd_gain = 100 * np.mean(1 - np.nanstd(without, axis=0) / np.nanstd(with_outliers, axis=0))
    return float(mean_gain), float(sd_gain)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--reps", type=int, default=40)
    parser.add_argument("--seeds", type=int, nargs="+", default=[11, 12, 13])
    args = parser.parse_args(argv)
    tables = kinect_noise.load_tables()
    truths = {"standing": simulate_truth("squat", args.reps, seed=3),
              "sitting": simulate_truth("seated_knee_extension", args.reps, seed=3)}  # fmt: skip
    print("| device | pose | view | paper mean / SD gain, % | simulated mean gain, % (per seed) | simulated SD gain, % "
          "(per seed) | outlier fraction, % (median, max) | jump, m (median, range) | capped joints |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|")
    for device in kinect_noise.DEVICES:
        for pose in kinect_noise.POSES:
            truth = truths[pose]
            for view in kinect_noise.VIEWS:
                got = []
                for seed in args.seeds:
                    measured, mask = kinect_noise.add_kinect_noise(
                        truth, device=device, view_deg=view, pose=pose, rng=np.random.default_rng(seed)
                    )
                    d = np.linalg.norm(measured.positions - truth.positions, axis=-1)
                    got.append(gains(d, measured.state == skeleton.TRACKED, mask))
                key = (device, pose, view)
                fraction, jump = kinect_noise.outlier_law(tables.offset_mean[key], tables.offset_sd[key],
                                                          *tables.gain_pct[key])  # fmt: skip
                capped = [skeleton.JOINTS[j] for j in np.flatnonzero(fraction >= kinect_noise.OUTLIER_FRACTION_MAX)]
                paper = tables.gain_pct[device, pose, view]
                m = np.array(got)
                print(f"| {device} | {pose} | {view}° | {paper[0]:g} / {paper[1]:g} | {np.median(m[:, 0]):.1f} "
                      f"({'/'.join(f'{x:.1f}' for x in m[:, 0])}) | {np.median(m[:, 1]):.1f} "
                      f"({'/'.join(f'{x:.1f}' for x in m[:, 1])}) | {100 * np.median(fraction):.1f}, "
                      f"{100 * fraction.max():.1f} | {np.median(jump):.2f}, {jump.min():.2f}-{jump.max():.2f} | "
                      f"{', '.join(capped) or '—'} |", flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
