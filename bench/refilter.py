"""Re-filtering a stored session (`coach-server reanalyze --pipeline`) against the agent's own filtering and the truth.

    .venv/bin/python -m bench.refilter [--exercises elbow_flexion squat ...] [--seeds 0 1 2] [--reps 10]

Per simulated set (kinect_agent.sources.simulator.simulate, as the demo's agents record them): repetitions and range
of motion (backend.analysis.report.analyze_recording, the server's analysis) of
  truth     the simulator's exact recording;
  before    the file as agents wrote it before session_file.as_stored: the pipeline filtered the recording in
            memory, the file stores its raw recording rounded to the 2**-10 m grid;
  refilter  the server filtering that stored raw recording again with the same settings (today's for the device),
            which is also what agents write now (make_payload filters as_stored(rec));
  stale     a file the agent filtered with other settings (sigma_tracked_m 0.03 m), whose re-filter is `refilter`.
and the largest difference between the `before` and `refilter` filtered positions (mm). One JSON line per set.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

DEFAULT_EXERCISES = ("elbow_flexion", "shoulder_abduction", "squat", "seated_knee_extension")


def _reps_rom(rec, spec, filtered=None, angle_sd=None) -> list[float]:
    from backend.analysis.report import analyze_recording

    r = analyze_recording(rec, spec, filtered=filtered, angle_sd=angle_sd)
    return [r.repetitions, round(r.rom_deg, 1) if r.rom_deg is not None else None]


def one_set(exercise: str, seed: int, reps: int) -> dict[str, object]:
    """Returns {exercise, seed, truth/before/refilter/stale: [repetitions, ROM degrees], max_diff_mm, seconds}."""
    from backend.exercises.library import EXERCISES
    from kinect_agent.formats import session_file as sf
    from kinect_agent.processing.config import PipelineConfig, config_for_device
    from kinect_agent.processing.pipeline import process
    from kinect_agent.sources.simulator import simulate

    spec = EXERCISES[exercise]
    measured, truth, _ = simulate(exercise, reps, seed=seed)
    measured.meta.exercise = exercise
    t0 = time.perf_counter()
    stored = sf.as_stored(measured)
    today = config_for_device(measured.meta.device)
    before = process(measured, config=today)  # the agent's filtering before as_stored
    again = process(stored, config=today)  # the server's re-filter of the stored raw (= the agent's now)
    stale = process(stored, config=PipelineConfig(sigma_tracked_m=0.03))
    diff = np.abs(sf.as_stored(before.filtered).positions - sf.as_stored(again.filtered).positions)
    return {
        "exercise": exercise,
        "seed": seed,
        "truth": _reps_rom(truth, spec, truth),
        "before": _reps_rom(stored, spec, before.filtered, before.angle_sd),
        "refilter": _reps_rom(stored, spec, again.filtered, again.angle_sd),
        "stale": _reps_rom(stored, spec, stale.filtered, stale.angle_sd),
        "max_diff_mm": round(float(np.nanmax(diff)) * 1000, 1),
        "seconds": round(time.perf_counter() - t0, 1),
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--exercises", nargs="+", default=list(DEFAULT_EXERCISES))
    p.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    p.add_argument("--reps", type=int, default=10)
    args = p.parse_args()
    for exercise in args.exercises:
        for seed in args.seeds:
            print(json.dumps(one_set(exercise, seed, args.reps)), flush=True)


if __name__ == "__main__":
    main()
