"""GET /api/v1/sessions/{id}: the metrics document as stored, typed (OpenAPI), and older stored documents upgraded."""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path
from typing import Any

import sqlalchemy as sa

from backend.sessions.models import SessionMetric
from kinect_agent.analysis.document import SCHEMA_VERSION, AnalysisDocument
from tests.backend.khs_files import make_processed_khs

DOCUMENTS = Path(__file__).parents[1] / "kinect_agent" / "analysis" / "documents"
T0 = dt.datetime(2026, 11, 2, 9, 0, tzinfo=dt.UTC)


def test_the_api_returns_the_stored_document_unchanged(client, db_session, upload, auth_headers):
    session_id, _, therapist = upload(make_processed_khs("shoulder_abduction", 3, seed=4), "shoulder_abduction")
    stored = db_session.scalar(sa.select(SessionMetric.document).where(SessionMetric.session_id == session_id))
    assert stored["schema_version"] == SCHEMA_VERSION and list(stored) == ["schema_version", *list(stored)[1:]]
    response = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(therapist))
    assert response.status_code == 200, response.text
    metrics, texts = _without_reason_texts(response.json()["metrics"])
    assert json.dumps(metrics) == json.dumps(stored)  # same keys, order and numbers; reasons' texts added
    assert texts and all(isinstance(t, str) and t for t in texts), "each reason in words (English: the therapist's)"
    assert set(stored) == set(AnalysisDocument.model_fields)


def _without_reason_texts(metrics: dict[str, Any]) -> tuple[dict[str, Any], list[Any]]:
    """Returns the metrics with the text of every reason and indicator basis None (as stored), and the texts."""
    texts: list[Any] = []

    def plain(reason: dict[str, Any]) -> dict[str, Any]:
        texts.append(reason["text"])
        return reason | {"text": None}

    out = dict(metrics)
    out["quality"] = out["quality"] | {"reasons": [plain(r) for r in out["quality"]["reasons"]]}
    withheld = out["range_of_motion_95_withheld"]
    out["range_of_motion_95_withheld"] = None if withheld is None else {k: plain(v) for k, v in withheld.items()}
    out["balance_missing"] = None if out["balance_missing"] is None else plain(out["balance_missing"])
    out["indicators"] = {name: item | {"basis": plain(item["basis"])} for name, item in out["indicators"].items()}
    missing = out["indicators"]["balance"]["missing"]
    if missing is not None:
        out["indicators"] = out["indicators"] | {"balance": out["indicators"]["balance"] | {"missing": plain(missing)}}
    return out, texts


def test_a_document_stored_before_schema_versions_is_returned_upgraded(
    client, make_patient_with_therapist, auth_headers, exercise, store
):
    older = json.loads((DOCUMENTS / "schema1_2026-11-23.json").read_text(encoding="utf-8"))
    patient, therapist = make_patient_with_therapist()
    row = store(patient, exercise, T0, doc=older)
    response = client.get(f"/api/v1/sessions/{row.id}", headers=auth_headers(therapist))
    assert response.status_code == 200, response.text
    metrics = response.json()["metrics"]
    assert metrics["schema_version"] == SCHEMA_VERSION and metrics["peak_end"] == "max"
    assert metrics["range_of_motion_95"] is None and metrics["analysis_version"] is None
    assert {k: metrics[k] for k in older if k not in ("repetition_list", "balance", "indicators")} == {
        k: v for k, v in older.items() if k not in ("repetition_list", "balance", "indicators")
    }


def test_progress_reads_the_indicators_of_an_older_document(client, make_user, auth_headers, exercise, store):
    older = json.loads((DOCUMENTS / "schema1_2026-11-23.json").read_text(encoding="utf-8"))
    patient = make_user("patient")
    store(patient, exercise, T0, doc=older)
    response = client.get(f"/api/v1/patients/{patient.id}/progress", headers=auth_headers(patient))
    assert response.status_code == 200, response.text
    indicators = response.json()["points"][0]["indicators"]
    flexibility = {"id": "flexibility_normal_range", "params": {"angle": "shoulder_abduction_L", "low": 0, "high": 180},
                   "text": "median amplitude of the left shoulder abduction over the repetitions, against its normal "
                   "range of 0 to 180°"}  # fmt: skip
    assert indicators["flexibility"] == older["indicators"]["flexibility"] | {"basis": flexibility}
    balance = {"id": "balance_sway", "params": {"good": 1, "poor": 6},
               "text": "sway of the trunk and hips while standing: 1 cm/s scores 100, 6 cm/s scores 0"}  # fmt: skip
    assert indicators["balance"] == older["indicators"]["balance"] | {"interval": None, "missing": None,
                                                                        "basis": balance}  # fmt: skip


def test_progress_says_why_balance_is_missing_in_the_readers_language(client, make_user, auth_headers, exercise, store):
    english = json.loads((DOCUMENTS / "schema2.json").read_text(encoding="utf-8"))  # before reason ids
    english["indicators"]["balance"] |= {"missing": "the recording is too short", "score": None, "value": None}
    patient = make_user("patient")
    store(patient, exercise, T0, doc=english)
    response = client.get(f"/api/v1/patients/{patient.id}/progress", headers=auth_headers(patient) | {
        "Accept-Language": "fr"})  # fmt: skip
    assert response.status_code == 200, response.text
    assert response.json()["points"][0]["indicators"]["balance"]["missing"] == {
        "id": "recording_too_short", "params": {}, "text": "l’enregistrement est trop court"}  # fmt: skip


def test_openapi_describes_the_metrics_document(client):
    schemas = client.get("/openapi.json").json()["components"]["schemas"]
    metrics = schemas["SessionOut"]["properties"]["metrics"]
    assert {"$ref": "#/components/schemas/AnalysisDocument"} in metrics["anyOf"]
    document = schemas["AnalysisDocument"]
    assert set(document["properties"]) == set(AnalysisDocument.model_fields)
    assert document["properties"]["duration_s"]["description"].startswith("recording length, s")
    progress = schemas["ProgressPoint"]["properties"]["indicators"]
    assert {"$ref": "#/components/schemas/Indicators"} in progress["anyOf"]


def test_a_stored_reason_id_no_message_has_is_named_not_hidden(client, make_user, auth_headers, exercise, store):
    today = json.loads((DOCUMENTS / "schema4.json").read_text(encoding="utf-8"))
    today["quality"] |= {"ok": False, "reasons": [{"id": "too_blurry", "params": {}, "text": None}]}
    patient = make_user("patient")
    row = store(patient, exercise, T0, doc=today)
    headers = auth_headers(patient)
    listed = client.get(f"/api/v1/patients/{patient.id}/progress", headers=headers)
    assert listed.status_code == 200 and listed.json()["points"][0]["indicators"] is not None, "the rest still reads"
    response = client.get(f"/api/v1/sessions/{row.id}", headers=headers)
    assert response.status_code == 500, response.text
    assert response.json()["error"] == "MetricsUnreadable"
    assert "quality.reasons.0" in response.json()["detail"] and "'too_blurry'" in response.json()["detail"]
