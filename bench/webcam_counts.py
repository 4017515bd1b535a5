"""Repetition counts of webcam-like sets: the stored session's count (backend.analysis.report.analyze_recording on
the filtered recording) with the webcam's filter, with the former chain filter, and on the unfiltered landmarks.

    nice -n 10 .venv/bin/python bench/webcam_counts.py [--reps 5] [--seeds 0 1]

Input: every simulated exercise the server knows (kinect_agent.sources.simulator.simulate_truth, the exact motion),
made webcam-like by tests/webcam_like.py (as the webcam filter's tests do):
jitter 10 mm across the image and 25 mm in depth, the hips' distance jittering 30 mm, and (second row of each case)
a sixth of the set where left and right flicker. "live" is the camera set's live count at the set's end (the
server's path: the webcam's live filter frame by frame on the session file's grid, LiveCount with the webcam's rules,
final()); "stored" (the shipped row) must equal it in every set.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from backend.analysis.report import analyze_recording  # noqa: E402
from backend.exercises.library import EXERCISES as LIBRARY  # noqa: E402
from kinect_agent.analysis.live import LiveCount, counting_params  # noqa: E402
from kinect_agent.formats.session_file import on_grid  # noqa: E402
from kinect_agent.processing.config import config_for_device  # noqa: E402
from kinect_agent.processing.online import live_filter  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402
from kinect_agent.sources.simulator import EXERCISES, simulate_truth  # noqa: E402
from tests.webcam_like import webcam_like  # noqa: E402


def live_count(raw: Recording, angles: tuple[str, ...]) -> int:
    """Returns the camera set's live count at its end (backend/camera/live_count.py's path, frame by frame)."""
    filt, counter = live_filter(config_for_device("webcam")), LiveCount(angles, params=counting_params("webcam"))
    for k in range(raw.n_frames):
        t = float(raw.t[k])
        counter.add(t, raw.positions[k], raw.state[k], filt.step(t, raw.positions[k], raw.state[k]))
    return counter.final()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    args = parser.parse_args()
    webcam = config_for_device("webcam")
    chain = webcam.model_copy(update={"offline_filter": "chain", "remove_outliers": True})
    methods = {"raw": None, "chain (before)": chain, "stored (shipped)": webcam, "live": "live"}
    off = {(m, s): 0 for m in methods for s in (False, True)}
    cases = {s: 0 for s in (False, True)}
    differ = 0
    exercises = [e for e in EXERCISES if e in LIBRARY]
    for exercise in exercises:
        for seed in args.seeds:
            truth = simulate_truth(exercise, args.reps, seed=seed)
            for swaps in (False, True):
                raw = webcam_like(truth, seed, swaps)
                raw = raw.replace(positions=on_grid(raw.positions))  # as a stored session file holds them
                counts = []
                for name, config in methods.items():
                    if config == "live":
                        n = live_count(raw, tuple(LIBRARY[exercise].defining_angles))
                        differ += int(n != counts[-1])
                    else:
                        filtered = None if config is None else process(raw, config=config).filtered
                        n = int(analyze_recording(raw, LIBRARY[exercise], filtered=filtered).repetitions)
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
    print(f"live != stored in {differ} of {sum(cases.values())} sets")


if __name__ == "__main__":
    main()
