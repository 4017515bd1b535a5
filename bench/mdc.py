"""Minimal detectable change per exercise from repeated simulated sessions of the same patients (issue 13).

    .venv/bin/python bench/mdc.py [--patients 3] [--sessions 6] [--reps 5] [--json out.json]

Each simulated patient keeps one body (bone lengths) over its sessions; every session draws a new execution (the
simulator's per-repetition amplitude and timing) and new Kinect errors (Kinect 2, facing the camera), goes through
the agent's pipeline and the server's analysis (report.analyze_recording with the angle SDs), exactly as an upload.
Per exercise and metric (rom_deg: median repetition amplitude of the defining angle; range_deg and max_deg of the
defining angle; repetitions):
    SEM     = sqrt(mean over patients of the within-patient variance of the measured metric)   (test-retest)
    MDC95   = 1.96 · √2 · SEM
    SEM_meas, MDC95_meas: the same from the measurement error alone (measured − true metric of each session);
    the test-retest figure also holds the session-to-session variation of the simulated execution.
"""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np

from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.analysis.report import analyze_recording
from kinect_agent.processing.pipeline import process
from kinect_agent.sources import motions
from kinect_agent.sources.kinect_noise import add_kinect_noise
from kinect_agent.sources.simulator import EXERCISES as SIMULATED
from kinect_agent.sources.simulator import simulate_truth

METRICS = ("rom_deg", "range_deg", "max_deg", "repetitions")
Z = 1.96 * np.sqrt(2.0)


def _metrics(doc: dict[str, Any], angle: str) -> dict[str, float]:
    rom = doc["range_of_motion"][angle]
    return {"rom_deg": doc["rom_deg"], "range_deg": rom["range_deg"], "max_deg": rom["max_deg"],
            "repetitions": float(doc["repetitions"])}  # fmt: skip


def session(exercise: str, patient: int, k: int, reps: int) -> tuple[dict[str, float], dict[str, float]]:
    """Returns (measured, true) metrics of session k of patient `patient` doing `exercise`."""
    spec = EXERCISES[exercise]
    body = motions.random_body(np.random.default_rng([patient, 1]))
    seed = 1000 * patient + k
    truth = simulate_truth(exercise, reps, seed=seed, body=body)
    if truth.meta.pose is None:
        raise ValueError(f"the simulated {exercise} has no pose")
    measured, _ = add_kinect_noise(
        truth, device="kinect2", view_deg=0, pose=truth.meta.pose, rng=np.random.default_rng([seed, 2])
    )
    result = process(measured)
    doc = analyze_recording(measured, spec, filtered=result.filtered, angle_sd=result.angle_sd).model_dump(mode="json")
    true_doc = analyze_recording(truth, spec).model_dump(mode="json")
    angle = true_doc["defining_angle"]
    return _metrics(doc, angle), _metrics(true_doc, angle)


def mdc(values: np.ndarray) -> tuple[float, float]:
    """Returns (SEM, MDC95) from values (patients, sessions): the pooled within-patient SD."""
    sem = float(np.sqrt(np.nanmean(np.nanvar(values, axis=1, ddof=1))))
    return sem, Z * sem


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--patients", type=int, default=3)
    parser.add_argument("--sessions", type=int, default=6)
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--exercises", nargs="*", default=list(SIMULATED))
    parser.add_argument("--json")
    args = parser.parse_args(argv)
    report: dict[str, dict[str, Any]] = {}
    print(f"{'exercise':22s} {'metric':12s} {'SEM':>6s} {'MDC95':>6s} {'SEM_meas':>8s} {'MDC95_meas':>10s}")
    for exercise in args.exercises:
        shape = (args.patients, args.sessions)
        measured = {m: np.full(shape, np.nan) for m in METRICS}
        true = {m: np.full(shape, np.nan) for m in METRICS}
        for p in range(args.patients):
            for k in range(args.sessions):
                got, want = session(exercise, p + 1, k, args.reps)
                for m in METRICS:
                    measured[m][p, k] = np.nan if got[m] is None else got[m]
                    true[m][p, k] = np.nan if want[m] is None else want[m]
        report[exercise] = {}
        for m in METRICS:
            sem, value = mdc(measured[m])
            sem_meas, value_meas = mdc(measured[m] - true[m])
            report[exercise][m] = {"sem": round(sem, 2), "mdc95": round(value, 2),
                                   "sem_meas": round(sem_meas, 2), "mdc95_meas": round(value_meas, 2)}  # fmt: skip
            print(f"{exercise:22s} {m:12s} {sem:6.1f} {value:6.1f} {sem_meas:8.1f} {value_meas:10.1f}", flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(report, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
