"""Repetition counts of webcam-like sets: the stored session's count (backend.analysis.report.analyze_recording on
the filtered recording) with the webcam's filter, with the former chain filter, and on the unfiltered landmarks.

    nice -n 10 .venv/bin/python bench/webcam_counts.py [--reps 5] [--seeds 0 1]

Input: every simulated exercise the server knows (kinect_agent.sources.simulator.simulate_truth, the exact motion),
made webcam-like as the test of the webcam's filter does (tests/kinect_agent/processing/test_joint_smoother.py):
jitter 10 mm across the image and 25 mm in depth, the hips' distance jittering 30 mm, and (second row of each case)
a sixth of the set where left and right flicker. The live count is not here: it runs the online chain filter, which
the webcam's filter did not change.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from backend.analysis.report import analyze_recording  # noqa: E402
from backend.exercises.library import EXERCISES as LIBRARY  # noqa: E402
from kinect_agent.processing.config import config_for_device  # noqa: E402
from kinect_agent.processing.label_swaps import MIRROR  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402
from kinect_agent.recording import Metadata, Recording  # noqa: E402
from kinect_agent.sources.simulator import EXERCISES, simulate_truth  # noqa: E402


def webcam_like(truth: Recording, seed: int, swaps: bool) -> Recording:
    """Returns the truth with the webcam's measured errors (module docstring)."""
    rng = np.random.default_rng(seed)
    T = truth.n_frames
    pos = truth.positions + rng.normal(0.0, 1.0, truth.positions.shape) * np.array([0.01, 0.01, 0.025])
    pos[..., 2] += rng.normal(0.0, 0.03, (T, 1))
    if swaps:
        stretch = np.arange(T // 3, T // 3 + T // 6)
        flicker = stretch[rng.random(stretch.size) < 0.5]
        pos[flicker] = pos[flicker][:, MIRROR]
    meta = Metadata(device="webcam", rate_hz=truth.meta.rate_hz, exercise=truth.meta.exercise)
    return Recording(truth.t.copy(), pos, truth.state.copy(), meta)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    args = parser.parse_args()
    webcam = config_for_device("webcam")
    chain = webcam.model_copy(update={"offline_filter": "chain", "remove_outliers": True})
    methods = {"raw": None, "chain (before)": chain, "joints (shipped)": webcam}
    off = {(m, s): 0 for m in methods for s in (False, True)}
    cases = {s: 0 for s in (False, True)}
    exercises = [e for e in EXERCISES if e in LIBRARY]
    for exercise in exercises:
        for seed in args.seeds:
            truth = simulate_truth(exercise, args.reps, seed=seed)
            for swaps in (False, True):
                raw = webcam_like(truth, seed, swaps)
                counts = []
                for name, config in methods.items():
                    filtered = None if config is None else process(raw, config=config).filtered
                    n = int(analyze_recording(raw, LIBRARY[exercise], filtered=filtered)["repetitions"])
                    counts.append(n)
                    off[(name, swaps)] += int(n != args.reps)
                cases[swaps] += 1
                if len(set(counts)) > 1 or counts[0] != args.reps:
                    print(f"{exercise:36s} seed {seed} {'swaps' if swaps else '     '}: " + ", ".join(
                        f"{m} {c}" for m, c in zip(methods, counts, strict=True)), flush=True)  # fmt: skip
    print(f"{len(exercises)} exercises x seeds {args.seeds}, {args.reps} repetitions each; sets miscounted:")
    for swaps in (False, True):
        label = "with flickering swaps" if swaps else "without swaps"
        print(f"  {label:22s} " + ", ".join(f"{m} {off[(m, swaps)]} of {cases[swaps]}" for m in methods))


if __name__ == "__main__":
    main()
