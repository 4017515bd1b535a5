"""The four indicators of the paper (flexibility, endurance, strength, balance) from one analysis document.

Each indicator (kinect_agent.analysis.document.Indicator) is {"score": 0..100 or None, "value": the measured
number or None, "basis": how it was scored (a Basis: a message of kinect_agent.analysis.reasons.BASES and its
numbers, written in the reader's language by backend.session_texts.reasons), "quality_ok": the document's quality ok and
the value present, "previous": median value of the history or None}.
history = earlier documents of the same patient and exercise, oldest first (their own values are re-read, so a
change of definition applies to the whole history).
    flexibility  value = rom_deg (median repetition amplitude of the defining angle, degrees; None when withheld);
                 score = 100 · value / span of the exercise's normal range (ExerciseSpec.normal_range_deg), ≤ 100.
    endurance    value = repetitions; score = 100 · value / target_reps (the plan's prescription), ≤ 100; without a
                 target, 100 · value / median of the history's repetitions, ≤ 100; None without either.
    strength     sit-to-stand exercise: value = sit_to_stand.mean_s (20-80 % rise time, s);
                 score = 100 · clip((SLOW_RISE_S − value) / (SLOW_RISE_S − FAST_RISE_S), 0, 1), i.e. 100 at ≤ 0.5 s,
                 0 at ≥ 2 s. Other exercises: value = median over repetitions of amplitude / duration (deg/s, how fast
                 the patient moves through the range; the repetitions whose amplitude is withheld left out); score =
                 100 · value / the best of the history, ≤ 100, None without history.
    balance      value = balance.sway_velocity_m_s (trunk-and-hips sway while standing, m/s);
                 score = 100 · clip((POOR_SWAY − value) / (POOR_SWAY − GOOD_SWAY), 0, 1): 100 at ≤ 1 cm/s (quiet
                 standing of healthy adults), 0 at ≥ 6 cm/s; None when the patient did not stand still ≥ 2 s.
                 Also "interval": balance.sway_velocity_95 ([low, high] m/s or None) and "missing": the document's
                 balance_missing (why there is no value: a reason id and its numbers, or None).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from kinect_agent.analysis import reasons as why
from kinect_agent.analysis.document import AnalysisReport, BalanceIndicator, Indicator, Indicators
from kinect_agent.analysis.exercise import ExerciseSpec
from kinect_agent.analysis.reasons import Basis

FAST_RISE_S, SLOW_RISE_S = 0.5, 2.0
GOOD_SWAY, POOR_SWAY = 0.01, 0.06


def _clip100(x: float) -> float:
    return round(float(np.clip(x, 0.0, 100.0)), 1)


def _values(history: list[AnalysisReport], read: Callable[[AnalysisReport], float | None]) -> list[float]:
    out = []
    for doc in history:
        v = read(doc)
        if v is not None and np.isfinite(v):
            out.append(float(v))
    return out


def _previous(previous: list[float]) -> float | None:
    return round(float(np.median(previous)), 3) if previous else None


def _indicator(
    score: float | None, value: float | None, basis: Basis, doc: AnalysisReport, previous: list[float]
) -> Indicator:
    return Indicator(score=score, value=value, basis=basis, quality_ok=doc.quality.ok and value is not None,
                     previous=_previous(previous))  # fmt: skip


def _rom(doc: AnalysisReport) -> float | None:
    return doc.rom_deg


def _reps(doc: AnalysisReport) -> float | None:
    return doc.repetitions


def _rise(doc: AnalysisReport) -> float | None:
    return doc.sit_to_stand.mean_s if doc.sit_to_stand is not None else None


def _speed(doc: AnalysisReport) -> float | None:
    rates = [r.amplitude_deg / r.duration_s for r in doc.repetition_list
             if r.amplitude_deg is not None and r.duration_s > 0]  # fmt: skip
    return round(float(np.median(rates)), 2) if rates else None


def _sway(doc: AnalysisReport) -> float | None:
    return doc.balance.sway_velocity_m_s if doc.balance is not None else None


def flexibility(doc: AnalysisReport, exercise: ExerciseSpec, history: list[AnalysisReport]) -> Indicator:
    """Returns the flexibility indicator (module doc)."""
    lo, hi = exercise.normal_range_deg
    value = _rom(doc)
    score = _clip100(100.0 * value / (hi - lo)) if value is not None and hi > lo else None
    if doc.defining_angle is None:
        basis = why.BASIS_FLEXIBILITY_NO_ANGLE.basis(low=lo, high=hi)
    else:
        basis = why.BASIS_FLEXIBILITY.basis(angle=doc.defining_angle, low=lo, high=hi)
    return _indicator(score, value, basis, doc, _values(history, _rom))


def endurance(doc: AnalysisReport, target_reps: int | None, history: list[AnalysisReport]) -> Indicator:
    """Returns the endurance indicator (module doc)."""
    value = doc.repetitions
    previous = _values(history, _reps)
    score: float | None
    if target_reps:
        score, basis = _clip100(100.0 * value / target_reps), why.BASIS_ENDURANCE_TARGET.basis(target=target_reps)
    elif previous and np.median(previous) > 0:
        ref = float(np.median(previous))
        score, basis = _clip100(100.0 * value / ref), why.BASIS_ENDURANCE_USUAL.basis(usual=ref)
    else:
        score, basis = None, why.BASIS_ENDURANCE_NONE.basis()
    return _indicator(score, value, basis, doc, previous)


def strength(doc: AnalysisReport, exercise: ExerciseSpec, history: list[AnalysisReport]) -> Indicator:
    """Returns the strength indicator (module doc)."""
    if exercise.slug == "sit_to_stand":
        value = _rise(doc)
        score = None
        if value is not None:
            score = _clip100(100.0 * (SLOW_RISE_S - value) / (SLOW_RISE_S - FAST_RISE_S))
        basis = why.BASIS_STRENGTH_RISE.basis(fast=FAST_RISE_S, slow=SLOW_RISE_S)
        return _indicator(score, value, basis, doc, _values(history, _rise))
    value = _speed(doc)
    previous = _values(history, _speed)
    if value is not None and previous and max(previous) > 0:
        score, basis = (
            _clip100(100.0 * value / max(previous)),
            why.BASIS_STRENGTH_SPEED.basis(),
        )
    else:
        score, basis = None, why.BASIS_STRENGTH_SPEED_NONE.basis()
    return _indicator(score, value, basis, doc, previous)


def balance(doc: AnalysisReport, history: list[AnalysisReport]) -> BalanceIndicator:
    """Returns the balance indicator (module doc)."""
    value = _sway(doc)
    score = None
    if value is not None:
        score = _clip100(100.0 * (POOR_SWAY - value) / (POOR_SWAY - GOOD_SWAY))
    basis = why.BASIS_BALANCE_SWAY.basis(good=round(GOOD_SWAY * 100, 4), poor=round(POOR_SWAY * 100, 4))  # cm/s
    common = _indicator(score, value, basis, doc, _values(history, _sway))
    interval = doc.balance.sway_velocity_95 if doc.balance is not None else None
    missing = doc.balance_missing if value is None else None
    return BalanceIndicator(**common.model_dump(), interval=interval, missing=missing)


def indicators(
    doc: AnalysisReport, *, exercise: ExerciseSpec, target_reps: int | None, history: list[AnalysisReport]
) -> Indicators:
    """Returns the "flexibility", "endurance", "strength" and "balance" indicators of an analysis document.

    doc: report.analyze_recording output; history: earlier documents of the same patient and exercise, oldest
    first. Raises ValueError when doc is not an analysis of `exercise`.
    """
    if doc.exercise != exercise.slug:
        raise ValueError(f"doc is an analysis of {doc.exercise!r}, not of {exercise.slug!r}")
    if target_reps is not None and (isinstance(target_reps, bool) or not isinstance(target_reps, int)):
        raise ValueError(f"target_reps must be a whole number or None, got {target_reps!r}")
    return Indicators(
        flexibility=flexibility(doc, exercise, history),
        endurance=endurance(doc, target_reps, history),
        strength=strength(doc, exercise, history),
        balance=balance(doc, history),
    )
