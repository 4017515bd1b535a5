"""Minimal detectable change (MDC95) of each exercise's range of motion, measured by bench/mdc.py.

MDC95 = 1.96 · √2 · SEM, SEM the pooled within-patient SD of rom_deg (median repetition amplitude of the defining
angle, degrees) over repeated simulated sessions of the same patients (3 patients × 6 sessions × 5 repetitions,
Kinect 2 facing the camera, the agent's pipeline and the server's analysis; refitted 2026-11-28 on the simulator whose
tracking-loss jumps start at the Kinect's own estimate, issue 24 decision 4; bench/README.md). A change between two
sessions smaller than this is within what the measurement and the execution vary by.
"""

from __future__ import annotations

MDC95_ROM_DEG: dict[str, float] = {
    "shoulder_abduction": 16.8,
    "shoulder_flexion": 15.2,
    "elbow_flexion": 26.2,
    "seated_knee_extension": 15.5,
    "squat": 15.4,
    "sit_to_stand": 8.1,
    "standing_leg_raise": 10.7,
    "side_step": 6.8,
}


def rom_mdc95(slug: str) -> float | None:
    """Returns the MDC95 of rom_deg (degrees) of exercise `slug`, or None when it was not measured."""
    return MDC95_ROM_DEG.get(slug)


__all__ = ["MDC95_ROM_DEG", "rom_mdc95"]
