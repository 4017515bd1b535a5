"""Minimal detectable change (MDC95) of each exercise's range of motion, measured by bench/mdc.py.

MDC95 = 1.96 · √2 · SEM, SEM the pooled within-patient SD of rom_deg (median repetition amplitude of the defining
angle, degrees) over repeated simulated sessions of the same patients (3 patients × 6 sessions × 5 repetitions,
Kinect 2 facing the camera, the agent's pipeline and the server's analysis; bench/README.md, 2026-11-25). A change
between two sessions smaller than this is within what the measurement and the execution vary by.
"""

from __future__ import annotations

MDC95_ROM_DEG: dict[str, float] = {
    "shoulder_abduction": 18.1,
    "shoulder_flexion": 15.7,
    "elbow_flexion": 25.8,
    "seated_knee_extension": 4.4,
    "squat": 25.5,
    "sit_to_stand": 11.0,
    "standing_leg_raise": 9.5,
    "side_step": 8.7,
}


def rom_mdc95(slug: str) -> float | None:
    """Returns the MDC95 of rom_deg (degrees) of exercise `slug`, or None when it was not measured."""
    return MDC95_ROM_DEG.get(slug)


__all__ = ["MDC95_ROM_DEG", "rom_mdc95"]
