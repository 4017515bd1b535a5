"""Repetition counts of webcam-like sets: the stored session's count (kinect_agent.analysis.report.analyze_recording on
the filtered recording) with the webcam's filter, with the former chain filter, and on the unfiltered landmarks.

    nice -n 10 .venv/bin/python bench/webcam_counts.py [--reps 5] [--seeds 0 1] [--cases full shallow]

Input: every simulated exercise the server knows (kinect_agent.sources.simulator.simulate_truth, the exact motion),
made webcam-like by tests/webcam_like.py (as the webcam filter's tests do):
jitter 10 mm across the image and 25 mm in depth, the hips' distance jittering 30 mm, and (second row of each case)
a sixth of the set where left and right flicker. "live" is the camera set's live count at the set's end (the
server's path: the webcam's live filter frame by frame on the session file's grid, LiveCount with the webcam's rules
and its floor measured on the set, final()); "stored" (the shipped row) must equal it in every set.

--quick: only the stored and the live count (--no-live: the stored one), every set printed (a webcam set's stored
count is counted on the live filter's causal pass of the raw recording, live.counting_positions, whatever the
offline filter's output).

--cases shallow: the repetition floor's cases (bench/README.md, "Webcam counts: a floor measured on the set"), per
exercise of SHALLOW_EXERCISES and seed, live / stored count against the truth: SHALLOW repetitions of SHALLOW_DEG
(the simulator's amplitude of the defining movement, e.g. an older patient's mini squat) with a steady landmarker
and with a slow wobble of WOBBLE_MILD_M, and a patient standing (or sitting) still, nothing done, with a wobble of
WOBBLE_MILD_M and WOBBLE_STRONG_M (tests/webcam_like.py; the knee angle then wobbles by up to about 17 and 25
degrees). No swaps. "stored" here is analyze_recording of the raw recording: a webcam set's count is counted on the
live filter's causal pass of the raw recording (live.counting_positions), whatever the offline filter's output.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from kinect_agent.analysis.exercise import EXERCISES as LIBRARY  # noqa: E402
from kinect_agent.analysis.live import LiveCount  # noqa: E402
from kinect_agent.analysis.report import analyze_recording  # noqa: E402
from kinect_agent.formats.session_file import on_grid  # noqa: E402
from kinect_agent.processing.config import PipelineConfig, config_for_device  # noqa: E402
from kinect_agent.processing.online import live_filter  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402
from kinect_agent.sources.simulator import EXERCISES, simulate_truth  # noqa: E402
from tests.webcam_like import webcam_like  # noqa: E402

SHALLOW_EXERCISES = ("squat", "shoulder_abduction", "elbow_flexion", "seated_knee_extension", "standing_leg_raise",
                     "side_step", "standing_shoulder_abduction", "standing_shoulder_extension")  # fmt: skip
SHALLOW, SHALLOW_DEG = 5, 15.0
WOBBLE_MILD_M, WOBBLE_STRONG_M = 0.005, 0.01
# (label, amplitude degrees, wobble m, true count)
SHALLOW_CASES = (
    ("shallow 15, steady", SHALLOW_DEG, 0.0, SHALLOW),
    ("shallow 15, wobble 5 mm", SHALLOW_DEG, WOBBLE_MILD_M, SHALLOW),
    ("still, wobble 5 mm", 0.0, WOBBLE_MILD_M, 0),
    ("still, wobble 10 mm", 0.0, WOBBLE_STRONG_M, 0),
)


def live_count(raw: Recording, angles: tuple[str, ...]) -> int:
    """Returns the camera set's live count at its end (backend/camera/live_count.py's path, frame by frame)."""
    filt, counter = live_filter(config_for_device("webcam")), LiveCount(angles, device="webcam")
    for k in range(raw.n_frames):
        t = float(raw.t[k])
        counter.add(t, raw.positions[k], raw.state[k], filt.step(t, raw.positions[k], raw.state[k]))
    return counter.final()


def shallow(seeds: list[int]) -> None:
    """Prints live / stored counts of SHALLOW_CASES per exercise and seed, and the sets off the truth per case."""
    print(f"{'exercise':30s} {'case':24s} true  " + "  ".join(f"seed {s:<3d}" for s in seeds) + "  (live/stored)")
    off = {(label, m): 0 for label, *_ in SHALLOW_CASES for m in ("live", "stored")}
    differ = 0
    for exercise in SHALLOW_EXERCISES:
        spec = LIBRARY[exercise]
        for label, amplitude, wobble_m, true in SHALLOW_CASES:
            cells = []
            for seed in seeds:
                truth = simulate_truth(exercise, SHALLOW, seed=seed, amplitude_deg=amplitude)
                raw = webcam_like(truth, seed, False, wobble_m)
                raw = raw.replace(positions=on_grid(raw.positions))
                live = live_count(raw, tuple(spec.defining_angles))
                stored = int(analyze_recording(raw, spec).repetitions)
                off[(label, "live")] += int(live != true)
                off[(label, "stored")] += int(stored != true)
                differ += int(live != stored)
                cells.append(f"{live}/{stored}".ljust(8))
            print(f"{exercise:30s} {label:24s} {true:<4d}  " + "  ".join(cells), flush=True)
    n = len(SHALLOW_EXERCISES) * len(seeds)
    print(f"{len(SHALLOW_EXERCISES)} exercises x seeds {seeds}; sets off the true count:")
    for label, *_ in SHALLOW_CASES:
        print(f"  {label:24s} live {off[(label, 'live')]} of {n}, stored {off[(label, 'stored')]} of {n}")
    print(f"live != stored in {differ} of {n * len(SHALLOW_CASES)} sets")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--cases", choices=("full", "shallow"), default="full")
    parser.add_argument("--quick", action="store_true", help="live and stored only (stored without the offline filter)")
    parser.add_argument("--no-live", action="store_true", help="with --quick: the stored count only (seconds a set)")
    args = parser.parse_args()
    if args.cases == "shallow":
        shallow(args.seeds)
        return
    webcam = config_for_device("webcam")
    chain = webcam.model_copy(update={"offline_filter": "chain", "remove_outliers": True})
    # method -> the offline filter's settings of its stored count (None: the raw recording), or "live"
    methods: dict[str, PipelineConfig | str | None] = {
        "raw": None,
        "chain (before)": chain,
        "stored (shipped)": webcam,
        "live": "live",
    }
    if args.quick:  # the stored count does not depend on the offline filter's output (module docstring)
        methods = {"stored (shipped)": None} if args.no_live else {"stored (shipped)": None, "live": "live"}
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
                counts: list[int] = []
                for name, config in methods.items():
                    if config == "live":
                        n = live_count(raw, tuple(LIBRARY[exercise].defining_angles))
                        differ += int(n != counts[-1])
                    else:
                        filtered = process(raw, config=config).filtered if isinstance(config, PipelineConfig) else None
                        n = int(analyze_recording(raw, LIBRARY[exercise], filtered=filtered).repetitions)
                        if args.quick:
                            print(f"{exercise:36s} seed {seed} {'swaps' if swaps else '     '}: stored {n}", end="")
                    counts.append(n)
                    off[(name, swaps)] += int(n != args.reps)
                if args.quick:
                    print("" if args.no_live else f", live {counts[-1]}", flush=True)
                    cases[swaps] += 1
                    continue
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
