"""The analysis document's models: today's documents read back unchanged, every older stored shape still reads.

documents/ holds one stored document of each shape the server has written (backend/analysis/report.py's history):
schema1_2026-11-23 (01f63ce: the first metrics), schema1_2026-11-25 (c83a249: + 95 % intervals),
schema1_2026-11-27 (b6dadc9 + d8eeccf: + balance in standing phases, analysis version) and schema2 (today).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from pydantic import ValidationError

from kinect_agent.analysis.document import (
    SCHEMA_VERSION,
    AnalysisDocument,
    AnalysisReport,
    UnreadableDocument,
    read_document,
    read_if_readable,
    read_indicators,
    read_report,
)

DOCUMENTS = Path(__file__).parent / "documents"
OLDER = ["schema1_2026-11-23", "schema1_2026-11-25", "schema1_2026-11-27"]


def _stored(name: str) -> dict[str, Any]:
    return json.loads((DOCUMENTS / f"{name}.json").read_text(encoding="utf-8"))


def test_todays_document_reads_back_to_the_same_json() -> None:
    stored = _stored("schema2")
    doc = read_document(stored)
    assert doc.schema_version == SCHEMA_VERSION == 2
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
    assert _holds(dumped, stored)  # every stored value is still there; upgrading only adds keys


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


def test_a_report_without_indicators_reads_as_a_report() -> None:
    stored = {k: v for k, v in _stored("schema2").items() if k not in ("indicators", "analysis_version")}
    report = read_report(stored | {"source": "session.khs"})  # `coach-server analyze --json` adds "source"
    assert type(report) is AnalysisReport and report.exercise == "shoulder_abduction"
    assert type(read_report(_stored("schema1_2026-11-23"))) is AnalysisDocument


def test_an_unknown_schema_version_is_refused_by_name() -> None:
    with pytest.raises(UnreadableDocument, match="schema_version 3"):
        read_document(_stored("schema2") | {"schema_version": 3})


def test_a_document_missing_a_key_of_its_version_is_refused() -> None:
    stored = _stored("schema2")
    del stored["peak_end"]
    with pytest.raises(ValidationError, match="peak_end"):
        read_document(stored)


def test_an_unknown_key_is_refused() -> None:
    stored = _stored("schema2")
    stored["quality"]["score"] = 3
    with pytest.raises(ValidationError, match="quality.score"):
        read_document(stored)


def test_indicators_alone_read_from_any_shape() -> None:
    older = _stored("schema1_2026-11-23")["indicators"]
    indicators = read_indicators(older)
    assert indicators is not None and indicators.balance.interval is None
    assert indicators.endurance.model_dump() == older["endurance"]
    assert read_indicators({"flexibility": {"score": 1}}) is None and read_indicators(None) is None


def test_readers_that_show_not_measured_get_none_for_what_no_schema_reads() -> None:
    assert read_if_readable(None) is None and read_if_readable({"repetitions": 3}) is None
    assert read_if_readable(_stored("schema1_2026-11-25")) is not None


def test_the_openapi_schema_describes_every_field() -> None:
    schema = AnalysisDocument.model_json_schema()
    assert set(schema["required"]) >= set(AnalysisDocument.model_fields) - {"schema_version"}
    assert "degrees" in schema["properties"]["rom_deg"]["description"]
    assert schema["$defs"]["Balance"]["properties"]["sway_velocity_m_s"]["description"].endswith("m/s")
