"""The analysis document's models: today's documents read back unchanged, every older stored shape still reads.

documents/ holds one stored document of each shape the server has written (kinect_agent/analysis/report.py's history):
schema1_2026-11-23 (01f63ce: the first metrics), schema1_2026-11-25 (c83a249: + 95 % intervals),
schema1_2026-11-27 (b6dadc9 + d8eeccf: + balance in standing phases, analysis version), schema2 (4bb313d: the
reasons in English words), schema3 (schema2 as the analysis of 2026-11-27 wrote it, each reason a message id and its
numbers, the indicators' bases in English words), schema4 (schema3 as the analysis of 2026-11-28 wrote it, each basis
a message id and its numbers), schema5 (schema4 upgraded, range_of_motion_withheld None) and schema6 (today: schema5
upgraded, its repetitions' and rom_deg's withheld None).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from pydantic import ValidationError

from kinect_agent.analysis import reasons
from kinect_agent.analysis.document import (
    SCHEMA_VERSION,
    AnalysisDocument,
    AnalysisReport,
    UnreadableDocument,
    basis_of_text,
    read_document,
    read_if_readable,
    read_indicators,
    read_report,
    reason_of_text,
)
from kinect_agent.analysis.reasons import Basis, Reason

DOCUMENTS = Path(__file__).parent / "documents"
OLDER = ["schema1_2026-11-23", "schema1_2026-11-25", "schema1_2026-11-27"]
TODAY = "schema6"


def _stored(name: str) -> dict[str, Any]:
    return json.loads((DOCUMENTS / f"{name}.json").read_text(encoding="utf-8"))


def test_todays_document_reads_back_to_the_same_json() -> None:
    stored = _stored(TODAY)
    doc = read_document(stored)
    assert doc.schema_version == SCHEMA_VERSION == 6
    assert json.dumps(doc.model_dump(mode="json")) == json.dumps(stored)  # same keys, same order, same numbers


@pytest.mark.parametrize("name", OLDER)
def test_an_older_stored_document_reads_with_its_values(name: str) -> None:
    stored = _stored(name)
    doc = read_document(stored)
    assert doc.schema_version == SCHEMA_VERSION
    assert doc.repetitions == stored["repetitions"] == len(doc.repetition_list)
    assert doc.rom_deg == stored["rom_deg"] and doc.quality.ok is stored["quality"]["ok"]
    assert doc.balance is not None and doc.balance.sway_velocity_m_s == stored["balance"]["sway_velocity_m_s"]
    assert doc.indicators.flexibility.score == stored["indicators"]["flexibility"]["score"]
    assert [r.start_s for r in doc.repetition_list] == [r["start_s"] for r in stored["repetition_list"]]
    assert doc.peak_end == "max"  # what the session page assumed for documents without one
    assert all(r.peak_s is None for r in doc.repetition_list)
    dumped = doc.model_dump(mode="json")
    assert set(dumped) == set(AnalysisDocument.model_fields)
    bases = {name: item | {"basis": basis_of_text(item["basis"])} for name, item in stored["indicators"].items()}
    # every stored value is still there (each basis as its message); upgrading only adds keys
    assert _holds(dumped, stored | {"indicators": bases})


def _holds(upgraded: Any, stored: Any) -> bool:
    """True when every key and value of `stored` is in `upgraded` (recursively; lists item by item)."""
    if isinstance(stored, dict):
        return isinstance(upgraded, dict) and all(k in upgraded and _holds(upgraded[k], v) for k, v in stored.items())
    if isinstance(stored, list):
        return isinstance(upgraded, list) and len(upgraded) == len(stored) and all(map(_holds, upgraded, stored))
    return bool(upgraded == stored)


def test_the_first_shape_has_no_intervals_and_no_version() -> None:
    doc = read_document(_stored("schema1_2026-11-23"))
    assert doc.range_of_motion_95 is None and doc.repetitions_95 is None and doc.analysis_version is None
    assert doc.balance is not None and doc.balance.sway_velocity_95 is None and doc.balance.n_windows is None
    assert doc.indicators.balance.interval is None and doc.indicators.balance.missing is None


def test_the_balance_shape_keeps_its_intervals_and_version() -> None:
    doc = read_document(_stored("schema1_2026-11-27"))
    assert doc.analysis_version == "2026.11.27-balance" and doc.repetitions_95 is not None
    assert doc.balance is not None and doc.balance.sway_velocity_95 == doc.indicators.balance.interval
    assert doc.range_of_motion_95_withheld is None  # withheld intervals came later (ff532a0)


def test_a_document_of_schema_4_reads_with_its_ranges_unchecked() -> None:
    stored = _stored("schema4")
    doc = read_document(stored)
    assert doc.schema_version == 6 and doc.range_of_motion_withheld is None  # not checked against the raw data
    assert doc.model_dump(mode="json") == _stored(TODAY)


def test_a_document_of_schema_5_reads_with_its_peaks_checked() -> None:
    stored = _stored("schema5")
    doc = read_document(stored)
    assert doc.model_dump(mode="json") == _stored(TODAY)  # no peak past a limit: only the new keys, None
    assert all(r.withheld is None for r in doc.repetition_list) and doc.rom_deg_withheld is None


def test_a_stored_knee_peak_past_what_a_knee_bends_is_withheld_on_read() -> None:
    """A document of schema 5 holds the peaks, not the curves: a knee peak past 170° (UI-PRMD's Kinect on a
    sit to stand read 175-179°) is withheld with its reason, and the median amplitude with it."""
    stored = _stored("schema5")
    stored["defining_angle"] = "knee_flexion_L"
    peaks = [176.4, 150.2, 169.9]
    stored["repetition_list"] = [r | {"peak_deg": p} for r, p in zip(stored["repetition_list"], peaks, strict=True)]
    doc = read_document(stored)
    first, *others = doc.repetition_list
    assert (first.peak_deg, first.amplitude_deg) == (None, None)
    assert first.withheld == Reason(id="beyond_anatomy", params={"reached": 176, "limit": 170})
    assert [r.peak_deg for r in others] == peaks[1:] and all(r.withheld is None for r in others)
    assert doc.rom_deg is None and doc.fatigue.amplitude_slope_pct_per_rep is None
    assert doc.rom_deg_withheld == Reason(
        id="repetitions_beyond_anatomy", params={"withheld": 1, "count": 3, "reached": 176, "limit": 170}
    )
    assert read_document(doc.model_dump(mode="json")) == doc  # today's shape reads back the same


def test_a_report_without_indicators_reads_as_a_report() -> None:
    stored = {k: v for k, v in _stored(TODAY).items() if k not in ("indicators", "analysis_version")}
    report = read_report(stored | {"source": "session.khs"})  # `coach-server analyze --json` adds "source"
    assert type(report) is AnalysisReport and report.exercise == "shoulder_abduction"
    assert type(read_report(_stored("schema1_2026-11-23"))) is AnalysisDocument


def test_an_unknown_schema_version_is_refused_by_name() -> None:
    with pytest.raises(UnreadableDocument, match="schema_version 7"):
        read_document(_stored(TODAY) | {"schema_version": 7})


def test_a_document_missing_a_key_of_its_version_is_refused() -> None:
    stored = _stored(TODAY)
    del stored["peak_end"]
    with pytest.raises(ValidationError, match="peak_end"):
        read_document(stored)


def test_an_unknown_key_is_refused() -> None:
    stored = _stored(TODAY)
    stored["quality"]["score"] = 3
    with pytest.raises(ValidationError, match="quality.score"):
        read_document(stored)


def test_indicators_alone_read_from_any_shape() -> None:
    older = _stored("schema1_2026-11-23")["indicators"]
    indicators = read_indicators(older)
    assert indicators is not None and indicators.balance.interval is None
    assert indicators.endurance.model_dump(exclude={"basis"}) == {k: v for k, v in older["endurance"].items()
                                                                  if k != "basis"}  # fmt: skip
    assert indicators.endurance.basis == Basis(id="endurance_target", params={"target": 3})
    assert read_indicators({"flexibility": {"score": 1}}) is None and read_indicators(None) is None


def test_readers_that_show_not_measured_get_none_for_what_no_schema_reads() -> None:
    assert read_if_readable(None) is None and read_if_readable({"repetitions": 3}) is None
    assert read_if_readable(_stored("schema1_2026-11-25")) is not None


def test_the_openapi_schema_describes_every_field() -> None:
    schema = AnalysisDocument.model_json_schema()
    assert set(schema["required"]) >= set(AnalysisDocument.model_fields) - {"schema_version"}
    assert "degrees" in schema["properties"]["rom_deg"]["description"]
    assert schema["$defs"]["Balance"]["properties"]["sway_velocity_m_s"]["description"].endswith("m/s")


# one English text per reason as schema 1 and 2 stored it (backend/session_texts before 83dc753 wrote the same words),
# with the id and numbers schema 3 reads it as
# fmt: off
ENGLISH = {
    "only 12 frames (at least 30 needed)": ("too_few_frames", {"frames": 12, "needed": 30}),
    "only 1.2 s recorded (at least 3 s needed)": ("too_short", {"seconds": 1.2, "needed": 3.0}),
    "the body was tracked in 46% of the samples (at least 60% needed)":
        ("too_little_tracked", {"tracked": 0.46, "needed": 0.6}),
    "35% of the samples were tracking errors (at most 20% allowed)":
        ("too_many_errors", {"errors": 0.35, "allowed": 0.2}),
    "the measured positions have gaps": ("gaps", {}),
    "shoulder rotation is undefined while the elbow is straight, so it has no interval": ("rotation_undefined", {}),
    "the angle is defined in only 41% of the frames (the limb was out of its plane)":
        ("out_of_plane", {"defined": 0.41}),
    "the joints of this angle were tracked in only 52% of the frames": ("joints_untracked", {"tracked": 0.52}),
    "the angle or its uncertainty is unknown in every frame, or it spun through a full turn": ("unknown_angle", {}),
    "the tracking is too uncertain: a 95 % interval would span 74° (at most 60° is shown)":
        ("too_uncertain", {"width": 74.0, "most": 60.0}),
    "the recording is too short": ("recording_too_short", {}),
    "the patient was seated or crouching: balance is measured while standing": ("not_standing", {}),
    "the patient never stood still with both feet down for 2.5 s in total (steps, a raised leg or a bent trunk do not "
    "count)": ("never_still", {"seconds": 2.5}),
    # newer than schema 3 (never stored as words), read back all the same, as every message is
    "the filtered curve reaches 12° beyond what the camera measured": ("beyond_raw", {"by": 12.0}),
    "the curve reaches 175°, more than the joint can bend (170°): the camera lost the limb":
        ("beyond_anatomy", {"reached": 175.0, "limit": 170.0}),
    "in 3 of 8 repetitions the curve reaches up to 178°, more than the joint can bend (170°): the camera lost the "
    "limb": ("repetitions_beyond_anatomy", {"withheld": 3, "count": 8, "reached": 178.0, "limit": 170.0}),
}
# fmt: on


def test_every_english_reason_upgrades_to_its_id_and_numbers() -> None:
    assert {id_ for id_, _ in ENGLISH.values()} == set(reasons.BY_ID), "one example per message"
    for text, (id_, params) in ENGLISH.items():
        reason = Reason.model_validate(reason_of_text(text))
        assert (reason.id, reason.params, reason.text) == (id_, params, None), text
        assert all(type(v) is int for v in reason.params.values()) == (id_ == "too_few_frames" or not params), reason


def test_the_english_document_of_schema_2_reads_with_ids_and_its_other_values_unchanged() -> None:
    stored = _stored("schema2")
    doc = read_document(stored)
    withheld = doc.range_of_motion_95_withheld
    assert withheld is not None and withheld["shoulder_abduction_L"] == Reason(
        id="too_uncertain", params={"width": 218, "most": 60})  # fmt: skip
    assert withheld["shoulder_rotation_L"] == Reason(id="rotation_undefined")
    dumped = doc.model_dump(mode="json")
    assert dumped == _stored(TODAY), "schema 2 upgraded is today's document of the same session"


def test_reasons_of_schema_2_in_every_place_upgrade_and_unknown_texts_stay_texts() -> None:
    stored = _stored("schema2")
    texts = list(ENGLISH)
    older = "an analysis of 2026-11-20 wrote this"  # matches no message (nor does a reworded one)
    stored["quality"] = stored["quality"] | {"ok": False, "reasons": [texts[2], older, texts[4]]}
    stored["balance"], stored["balance_missing"] = None, texts[12]
    stored["indicators"]["balance"] |= {"missing": texts[11], "score": None, "value": None}
    stored["range_of_motion_95_withheld"]["shoulder_abduction_L"] = texts[0].replace("frames", "images")
    doc = read_document(stored)
    assert [(r.id, r.params, r.text) for r in doc.quality.reasons] == [
        ("too_little_tracked", {"tracked": 0.46, "needed": 0.6}, None),
        (None, {}, older),
        ("gaps", {}, None),
    ]
    assert doc.balance_missing == Reason(id="never_still", params={"seconds": 2.5})
    assert doc.indicators.balance.missing == Reason(id="not_standing")
    assert doc.range_of_motion_95_withheld is not None
    kept = doc.range_of_motion_95_withheld["shoulder_abduction_L"]
    assert kept.id is None and kept.text == "only 12 images (at least 30 needed)"
    again = read_document(doc.model_dump(mode="json"))
    assert again == doc, "a text reason is stored as a text in schema 3 and 4"


def test_indicators_alone_of_schema_2_read_their_reason() -> None:
    indicators = _stored("schema2")["indicators"]
    indicators["balance"] |= {"missing": "the recording is too short", "score": None, "value": None}
    read = read_indicators(indicators)
    assert read is not None and read.balance.missing == Reason(id="recording_too_short")
    assert read_indicators(read.model_dump(mode="json")) == read


def test_an_unknown_reason_id_or_wrong_numbers_are_refused_by_name() -> None:
    stored = _stored(TODAY)
    stored["quality"]["reasons"] = [{"id": "too_blurry", "params": {}}]
    with pytest.raises(ValidationError, match="unknown reason id 'too_blurry'"):
        read_document(stored)
    stored["quality"]["reasons"] = [{"id": "too_few_frames", "params": {"frames": 3}}]
    with pytest.raises(ValidationError, match=r"reason 'too_few_frames' needs the numbers \['frames', 'needed'\]"):
        read_document(stored)
    stored["quality"]["reasons"] = [{"id": None, "params": {}}]
    with pytest.raises(ValidationError, match="a reason without an id is a text"):
        read_document(stored)
    assert read_if_readable(stored) is None


# one English basis per message as schema 1 to 3 stored it (the indicators, then backend/analysis/indicators.py, from
# 2026-11-24 to schema 3 wrote these words), with the id and values schema 4 reads it as
ENGLISH_BASES = {
    "median amplitude of knee_flexion_R against the normal range 0..135 deg": (
        "flexibility_normal_range", {"angle": "knee_flexion_R", "low": 0, "high": 135}),
    "median amplitude of None against the normal range -10..90.5 deg": ("flexibility_no_angle", {"low": -10,
                                                                                                  "high": 90.5}),
    "repetitions against the target of 12": ("endurance_target", {"target": 12}),
    "repetitions against the usual 8.5 of earlier sessions": ("endurance_usual", {"usual": 8.5}),
    "repetitions; no target and no earlier session to compare with": ("endurance_no_reference", {}),
    "sit-to-stand rise time (20-80 %), 0.5 s scores 100, 2 s scores 0": ("strength_rise_time", {"fast": 0.5,
                                                                                                 "slow": 2}),
    "movement speed (deg/s) against the best earlier session": ("strength_speed_best", {}),
    "movement speed (deg/s); no earlier session to compare with": ("strength_speed_no_reference", {}),
    "trunk-and-hips sway while standing, 1 cm/s scores 100, 6 cm/s 0": ("balance_sway", {"good": 1, "poor": 6}),
}  # fmt: skip


def test_every_english_basis_upgrades_to_its_id_and_values() -> None:
    assert {id_ for id_, _ in ENGLISH_BASES.values()} == set(reasons.BASES_BY_ID), "one example per message"
    for text, (id_, params) in ENGLISH_BASES.items():
        basis = Basis.model_validate(basis_of_text(text))
        assert (basis.id, basis.params, basis.text) == (id_, params, None), text


def test_the_bases_of_schema_3_upgrade_and_older_wordings_stay_texts() -> None:
    stored = _stored("schema3")
    older = "body-centre sway while standing still, 1 cm/s scores 100, 6 cm/s 0"  # 2026-11-23's balance, another method
    stored["indicators"]["balance"]["basis"] = older
    doc = read_document(stored)
    assert doc.indicators.flexibility.basis == Basis(
        id="flexibility_normal_range", params={"angle": "shoulder_abduction_L", "low": 0, "high": 180})  # fmt: skip
    assert doc.indicators.balance.basis == Basis(id=None, text=older)
    assert read_document(doc.model_dump(mode="json")) == doc, "a text basis is stored as a text in schema 4"
    assert read_indicators(stored["indicators"]) == doc.indicators, "the dashboard reads the indicators alone the same"


def test_a_reason_is_no_basis_and_a_basis_needs_its_angle_by_name() -> None:
    stored = _stored(TODAY)
    stored["indicators"]["endurance"]["basis"] = {"id": "too_short", "params": {"seconds": 1, "needed": 3}}
    with pytest.raises(ValidationError, match="unknown basis id 'too_short'"):
        read_document(stored)
    stored["indicators"]["endurance"]["basis"] = {"id": "flexibility_normal_range",
                                                  "params": {"angle": 3, "low": 0, "high": 90}}  # fmt: skip
    with pytest.raises(ValidationError, match="flexibility_normal_range"):
        read_document(stored)
