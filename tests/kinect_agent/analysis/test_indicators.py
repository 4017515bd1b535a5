"""The four indicators: scores against the plan's target, the normal range and the patient's own history."""

from __future__ import annotations

from typing import Any

import pytest

from kinect_agent.analysis import indicators as indicators_module
from kinect_agent.analysis.document import AnalysisReport, read_report
from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.analysis.report import analyze_recording
from kinect_agent.sources.simulator import simulate_truth

KEYS = {"score", "value", "basis", "quality_ok", "previous"}


def _doc(slug: str, reps: int, seed: int = 1, **kw) -> AnalysisReport:
    return analyze_recording(simulate_truth(slug, reps, seed=seed, **kw), EXERCISES[slug])


def indicators(doc: AnalysisReport, **kw: Any) -> dict[str, Any]:
    """The indicators of doc as their JSON."""
    return indicators_module.indicators(doc, **kw).model_dump(mode="json")


def test_every_indicator_has_score_value_basis_quality() -> None:
    doc = _doc("shoulder_abduction", 6, pose="standing")
    out = indicators(doc, exercise=EXERCISES["shoulder_abduction"], target_reps=10, history=[])
    assert set(out) == {"flexibility", "endurance", "strength", "balance"}
    assert all(set(v) == KEYS for k, v in out.items() if k != "balance")
    assert set(out["balance"]) == KEYS | {"interval", "missing"}
    lo, hi = out["balance"]["interval"]
    assert lo <= out["balance"]["value"] <= hi and out["balance"]["missing"] is None
    assert out["endurance"]["score"] == 60.0 and out["endurance"]["value"] == 6
    assert doc.rom_deg is not None
    assert out["flexibility"]["score"] == pytest.approx(100 * doc.rom_deg / 180, abs=0.1)
    assert out["balance"]["score"] is not None and out["balance"]["quality_ok"]
    assert out["strength"]["score"] is None  # no history to compare the movement speed with


def test_history_is_the_reference_without_a_target() -> None:
    slug = "elbow_flexion"
    history = [_doc(slug, 8, seed=s) for s in (2, 3)]
    doc = _doc(slug, 4, seed=4)
    out = indicators(doc, exercise=EXERCISES[slug], target_reps=None, history=history)
    assert out["endurance"]["score"] == 50.0 and out["endurance"]["previous"] == 8
    assert out["strength"]["score"] is not None and 0 < out["strength"]["score"] <= 100


def test_sit_to_stand_strength_comes_from_the_rise_time() -> None:
    doc = _doc("sit_to_stand", 4, seed=2)
    out = indicators(doc, exercise=EXERCISES["sit_to_stand"], target_reps=5, history=[])
    assert doc.sit_to_stand is not None
    rise = doc.sit_to_stand.mean_s
    assert out["strength"]["value"] == rise
    assert out["strength"]["score"] == pytest.approx(100 * (2.0 - rise) / 1.5, abs=0.1)


def test_seated_session_has_no_balance_score() -> None:
    doc = _doc("elbow_flexion", 3, pose="sitting")
    out = indicators(doc, exercise=EXERCISES["elbow_flexion"], target_reps=3, history=[])
    assert out["balance"]["score"] is None and out["balance"]["quality_ok"] is False
    assert out["balance"]["missing"] == {"id": "not_standing", "params": {}, "text": None}


def test_document_of_another_exercise_is_refused() -> None:
    with pytest.raises(ValueError, match="squat"):
        indicators(_doc("elbow_flexion", 1), exercise=EXERCISES["squat"], target_reps=None, history=[])


def test_a_stored_history_document_gives_the_previous_value() -> None:
    slug = "elbow_flexion"
    history = [read_report(_doc(slug, 6, seed=6).model_dump(mode="json"))]  # as stored, as read back
    out = indicators(_doc(slug, 3, seed=5), exercise=EXERCISES[slug], target_reps=None, history=history)
    assert out["endurance"]["previous"] == 6 and out["endurance"]["score"] == 50.0
