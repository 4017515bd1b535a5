"""Balance on simulated Kinect v2 sessions: the trunk-and-hips sway measured after the agent's pipeline, against
the same measure on the exact (truth) recording, per exercise and seed.

    .venv/bin/python -m bench.balance [--seeds 5]

Prints, per standing exercise, the median over seeds of: the true sway velocity (cm/s), the measured one, their
difference, the share of the session counted as standing, how often the true value lies in the 95 % interval, and
how many sessions had no value.
"""

from __future__ import annotations

import argparse

import numpy as np

from kinect_agent.analysis import series
from kinect_agent.analysis.balance import sway
from kinect_agent.body.angles import joint_angles
from kinect_agent.processing.pipeline import process
from kinect_agent.recording import Recording
from kinect_agent.sources.simulator import simulate

EXERCISES = ("shoulder_abduction", "shoulder_flexion", "elbow_flexion", "squat", "side_step", "standing_leg_raise")


def _measure(rec: Recording) -> dict[str, object] | None:
    """Returns kinect_agent.analysis.balance.sway of the recording's smoothed positions (None: no standing phase)."""
    smoothed = series.smooth_positions(rec.t, rec.positions)
    return sway(rec.t, smoothed, joint_angles(smoothed))


def _number(values: dict[str, object], key: str) -> float:
    """Returns the number values[key] of a sway result."""
    value = values[key]
    if not isinstance(value, int | float):
        raise TypeError(f"sway's {key} is {value!r}, not a number")
    return value


def _interval(values: dict[str, object], key: str) -> tuple[float, float]:
    """Returns the interval values[key] ([low, high]) of a sway result."""
    value = values[key]
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise TypeError(f"sway's {key} is {value!r}, not an interval")
    low, high = value
    return low, high


def main() -> None:
    """Prints the table of the module doc."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=5)
    args = ap.parse_args()
    print("exercise            true cm/s  measured  diff  standing%  covered  none")
    for ex in EXERCISES:
        rows, none, covered = [], 0, 0
        for seed in range(args.seeds):
            measured, truth, _ = simulate(ex, 6, seed=seed)
            b_true, b = _measure(truth), _measure(process(measured).filtered)
            if b is None or b_true is None:
                none += 1
                continue
            v0, v = _number(b_true, "sway_velocity_m_s"), _number(b, "sway_velocity_m_s")
            lo, hi = _interval(b, "sway_velocity_95")
            covered += lo <= v0 <= hi
            rows.append((100 * v0, 100 * v, 100 * (v - v0), 100 * _number(b, "standing_s") / truth.duration))
        med = np.median(rows, axis=0) if rows else [np.nan] * 4
        cover = f"{covered:3d}/{len(rows):<3d}"
        print(f"{ex:20s} {med[0]:8.2f} {med[1]:9.2f} {med[2]:5.2f} {med[3]:9.0f}  {cover} {none:4d}")


if __name__ == "__main__":
    main()
