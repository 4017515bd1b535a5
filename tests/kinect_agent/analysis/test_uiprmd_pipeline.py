"""analyze (as analyze_file runs it: the agent's pipeline, then the metrics on its filtered output) counts the 10
segmented repetitions of UI-PRMD's lower-limb movements. Before the gate re-acquisition fix the filtered knee stuck in
fast squats and lunges (m01 s01: 4 repetitions, m01 s02: 6)."""

from __future__ import annotations

import pytest

from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.analysis.report import analyze_recording
from kinect_agent.processing.pipeline import process

from ._data import uiprmd


@pytest.mark.shared_data
@pytest.mark.parametrize(
    ("movement", "subject"),
    [("m01", "s01"), ("m01", "s02"), ("m03", "s04"), ("m04", "s05"), ("m05", "s04"), ("m06", "s02")],
)
def test_lower_limb_movement_after_pipeline_gives_ten_repetitions(data_dir, movement: str, subject: str) -> None:
    exercise = next(s for s in EXERCISES.values() if s.uiprmd_movement == movement)
    raw = uiprmd(data_dir, movement, subject)
    doc = analyze_recording(raw, exercise, filtered=process(raw).filtered).model_dump(mode="json")
    assert doc["measured_on"] == "filtered"
    starts = [r["start_s"] for r in doc["repetition_list"]]
    assert doc["repetitions"] == 10, f"{movement} {subject} ({exercise.slug}): repetitions start at {starts} s"
