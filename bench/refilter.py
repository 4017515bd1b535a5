"""Re-filtering a stored session (`coach-server reanalyze --pipeline`) against the agent's own filtering and the truth.

    .venv/bin/python -m bench.refilter [--exercises elbow_flexion squat ...] [--seeds 0 1 2] [--reps 10]
    .venv/bin/python -m bench.refilter --ui-prmd m01 m07 ... [--subject s01]   (real Kinect v2, ../shared/data)

Per simulated set (kinect_agent.sources.simulator.simulate, as the demo's agents record them): repetitions and range
of motion (kinect_agent.analysis.report.analyze_recording, the server's analysis) of
  truth     the simulator's exact recording;
  raw       the stored raw recording analysed without a filtered one (what the simulated Kinect measured);
  before    the file as agents wrote it before session_file.as_stored: the pipeline filtered the recording in
            memory, the file stores its raw recording rounded to the 2**-10 m grid;
  refilter  the server filtering that stored raw recording again with the same settings (today's for the device),
            which is also what agents write now (make_payload filters as_stored(rec));
  stale     a file the agent filtered with other settings (sigma_tracked_m 0.03 m), whose re-filter is `refilter`.
and the largest difference between the `before` and `refilter` filtered positions (mm). One JSON line per set.
--ui-prmd: the same for the 10 episodes of a UI-PRMD movement (Kinect v2, joined), without a truth.
"""

from __future__ import annotations

import argparse
import json
import time
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from kinect_agent.analysis.exercise import ExerciseSpec
    from kinect_agent.recording import Recording

DEFAULT_EXERCISES = ("elbow_flexion", "shoulder_abduction", "squat", "seated_knee_extension")


def _reps_rom(
    rec: Recording, spec: ExerciseSpec, filtered: Recording | None = None, angle_sd: dict[str, np.ndarray] | None = None
) -> list[float | None]:
    """Returns [repetitions, ROM degrees rounded to 0.1 (None: not measured)] of the server's analysis."""
    from kinect_agent.analysis.report import analyze_recording

    r = analyze_recording(rec, spec, filtered=filtered, angle_sd=angle_sd)
    return [r.repetitions, round(r.rom_deg, 1) if r.rom_deg is not None else None]


def one_set(exercise: str, seed: int, reps: int) -> dict[str, object]:
    """Returns {exercise, seed, truth/raw/before/refilter/stale: [repetitions, ROM degrees], max_diff_mm,
    seconds}."""
    from kinect_agent.analysis.exercise import EXERCISES
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
        "raw": _reps_rom(stored, spec),
        "before": _reps_rom(stored, spec, before.filtered, before.angle_sd),
        "refilter": _reps_rom(stored, spec, again.filtered, again.angle_sd),
        "stale": _reps_rom(stored, spec, stale.filtered, stale.angle_sd),
        "max_diff_mm": round(float(np.nanmax(diff)) * 1000, 1),
        "seconds": round(time.perf_counter() - t0, 1),
    }


UI_PRMD_EXERCISES = (  # m01-m10
    "deep_squat", "hurdle_step", "inline_lunge", "side_lunge", "sit_to_stand", "standing_active_straight_leg_raise",
    "standing_shoulder_abduction", "standing_shoulder_extension", "standing_shoulder_rotation",
    "standing_shoulder_scaption",
)  # fmt: skip


def real_set(movement: str, subject: str) -> dict[str, object]:
    """Returns one_set's fields (no truth) for the 10 episodes of a UI-PRMD movement m01-m10 of a subject."""
    from pathlib import Path

    from kinect_agent.analysis.exercise import EXERCISES
    from kinect_agent.formats import session_file as sf
    from kinect_agent.formats import ui_prmd
    from kinect_agent.processing.config import config_for_device
    from kinect_agent.processing.pipeline import process

    folder = Path(__file__).resolve().parents[2] / "shared" / "data" / "ui-prmd" / "Segmented Movements" / "Kinect"
    rec = ui_prmd.read_episodes(folder, movement=movement, subject=subject)
    spec = EXERCISES[UI_PRMD_EXERCISES[int(movement[1:]) - 1]]
    stored = sf.as_stored(rec)
    today = config_for_device(rec.meta.device)
    before, again = process(rec, config=today), process(stored, config=today)
    diff = np.abs(sf.as_stored(before.filtered).positions - sf.as_stored(again.filtered).positions)
    return {
        "exercise": f"UI-PRMD {movement} {subject} ({spec.slug})",
        "before": _reps_rom(stored, spec, before.filtered, before.angle_sd),
        "refilter": _reps_rom(stored, spec, again.filtered, again.angle_sd),
        "max_diff_mm": round(float(np.nanmax(diff)) * 1000, 1),
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--exercises", nargs="+", default=list(DEFAULT_EXERCISES))
    p.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    p.add_argument("--reps", type=int, default=10)
    p.add_argument("--ui-prmd", nargs="*", default=[], help="UI-PRMD movements (m01-m10) instead of simulated sets")
    p.add_argument("--subject", default="s01", help="UI-PRMD subject (s01-s05)")
    args = p.parse_args()
    if args.ui_prmd:
        for movement in args.ui_prmd:
            print(json.dumps(real_set(movement, args.subject)), flush=True)
        return
    for exercise in args.exercises:
        for seed in args.seeds:
            print(json.dumps(one_set(exercise, seed, args.reps)), flush=True)


if __name__ == "__main__":
    main()
