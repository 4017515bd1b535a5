"""CSV export: a zip whose tables a spreadsheet opens, holding the document's numbers and the angles per frame."""

from __future__ import annotations

import csv
import io
import zipfile

import numpy as np

from kinect_agent.analysis import reasons
from kinect_agent.analysis.angles import measured_angles
from kinect_agent.body.angles import ANGLE_NAMES, joint_angles
from kinect_agent.export.files import export


def _tables(data: bytes) -> dict[str, list[dict[str, str]]]:
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        return {n: list(csv.DictReader(io.StringIO(z.read(n).decode("utf-8")))) for n in z.namelist()}


def test_zip_holds_metrics_repetitions_and_both_angle_tables(squat_session):
    payload, doc = squat_session
    tables = _tables(export("csv", payload, document=doc).data)
    assert sorted(tables) == [
        "angles_filtered.csv",
        "angles_raw.csv",
        "metrics.csv",
        "recording.csv",
        "repetitions.csv",
    ]
    metrics = {r["metric"]: (r["value"], r["unit"]) for r in tables["metrics.csv"]}
    assert metrics["repetitions"] == ("3", "")
    assert float(metrics["duration"][0]) == doc.duration_s and metrics["duration"][1] == "s"
    assert float(metrics["knee_flexion_L.range"][0]) == doc.range_of_motion["knee_flexion_L"].range_deg
    assert float(metrics["indicator.endurance.score"][0]) == doc.indicators.endurance.score
    reps = tables["repetitions.csv"]
    assert [int(r["repetition"]) for r in reps] == [1, 2, 3]
    assert [float(r["amplitude_deg"]) for r in reps] == [r.amplitude_deg for r in doc.repetition_list]


def test_angle_tables_match_the_angles_of_each_recording(squat_session):
    payload, doc = squat_session
    tables = _tables(export("csv", payload, document=doc).data)
    filtered = payload.filtered
    expected_of = {  # raw: frame by frame; filtered: as the analysis measures it (the range of motion's series)
        "angles_raw.csv": joint_angles(payload.raw.positions),
        "angles_filtered.csv": measured_angles(filtered.t, filtered.positions).angles,
    }
    for name, rec in (("angles_raw.csv", payload.raw), ("angles_filtered.csv", filtered)):
        rows = tables[name]
        assert len(rows) == rec.n_frames and list(rows[0]) == ["time_s", *[f"{a}_deg" for a in ANGLE_NAMES]]
        expected = expected_of[name]["knee_flexion_R"]
        got = np.array([float(r["knee_flexion_R_deg"]) if r["knee_flexion_R_deg"] else np.nan for r in rows])
        np.testing.assert_allclose(got, expected, atol=0.006, err_msg=name)


def test_without_a_document_only_the_angle_tables_and_the_device_are_written(squat_session):
    payload, _ = squat_session
    assert sorted(_tables(export("csv", payload).data)) == ["angles_filtered.csv", "angles_raw.csv", "recording.csv"]


def test_the_same_session_gives_the_same_bytes(squat_session):
    payload, doc = squat_session
    assert export("csv", payload, document=doc).data == export("csv", payload, document=doc).data


def test_a_withheld_peak_is_an_empty_cell_with_its_reason(squat_session):
    """A repetition measured past what the knee bends (kinect_agent.analysis.anatomy) exports no amplitude nor peak,
    and says why; so does the median amplitude it withholds."""
    payload, doc = squat_session
    why = reasons.BEYOND_ANATOMY.reason(reached=176, limit=170)
    first, *others = doc.repetition_list
    lost = first.model_copy(update={"peak_deg": None, "amplitude_deg": None, "withheld": why})
    rom_why = reasons.REPETITIONS_BEYOND_ANATOMY.reason(withheld=1, count=3, reached=176, limit=170)
    withheld = doc.model_copy(update={"repetition_list": [lost, *others], "rom_deg": None, "rom_deg_withheld": rom_why})
    tables = _tables(export("csv", payload, document=withheld).data)
    reps = tables["repetitions.csv"]
    assert (reps[0]["peak_deg"], reps[0]["amplitude_deg"], reps[0]["withheld"]) == ("", "", "beyond_anatomy")
    assert all(r["peak_deg"] and r["withheld"] == "" for r in reps[1:]), reps
    metrics = {r["metric"]: r["value"] for r in tables["metrics.csv"]}
    assert metrics["repetition_amplitude_median"] == ""
    assert metrics["repetition_amplitude_median.withheld"] == "repetitions_beyond_anatomy"
    shown = {r["metric"]: r["value"] for r in _tables(export("csv", payload, document=doc).data)["metrics.csv"]}
    assert float(shown["repetition_amplitude_median"]) == doc.rom_deg
    assert shown["repetition_amplitude_median.withheld"] == ""
