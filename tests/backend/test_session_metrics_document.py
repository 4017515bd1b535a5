"""GET /api/v1/sessions/{id}: the metrics document as stored, typed (OpenAPI), and older stored documents upgraded."""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

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
    assert json.dumps(response.json()["metrics"]) == json.dumps(stored)  # same keys, order and numbers
    assert set(stored) == set(AnalysisDocument.model_fields)


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
    assert indicators["flexibility"] == older["indicators"]["flexibility"]
    assert indicators["balance"] == older["indicators"]["balance"] | {"interval": None, "missing": None}


def test_openapi_describes_the_metrics_document(client):
    schemas = client.get("/openapi.json").json()["components"]["schemas"]
    metrics = schemas["SessionOut"]["properties"]["metrics"]
    assert {"$ref": "#/components/schemas/AnalysisDocument"} in metrics["anyOf"]
    document = schemas["AnalysisDocument"]
    assert set(document["properties"]) == set(AnalysisDocument.model_fields)
    assert document["properties"]["duration_s"]["description"].startswith("recording length, s")
    progress = schemas["ProgressPoint"]["properties"]["indicators"]
    assert {"$ref": "#/components/schemas/Indicators"} in progress["anyOf"]
