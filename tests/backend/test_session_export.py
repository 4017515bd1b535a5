"""GET /api/v1/sessions/{id}/export?format=…: each format, its access rules, its audit and its errors."""

from __future__ import annotations

import datetime as dt
import io
import json
import zipfile
from typing import Any

import numpy as np
import pytest
from sqlalchemy import select

from backend.audit.models import AuditEvent
from backend.exercises.models import Exercise
from kinect_agent.formats import bvh
from kinect_agent.formats import session_file as sf
from tests.backend.khs_files import make_khs

T0 = dt.datetime(2026, 11, 2, 9, 0, tzinfo=dt.UTC)
R4B = pytest.importorskip("fhir.resources.R4B.bundle", reason="fhir.resources is in the test extra")


def _export(client, session_id: int, fmt: str, headers: dict[str, Any]):
    return client.get(f"/api/v1/sessions/{session_id}/export", params={"format": fmt}, headers=headers)


@pytest.mark.parametrize(
    ("fmt", "media_type", "file_name"),
    [("csv", "application/zip", "-csv.zip"), ("trc", "text/plain; charset=utf-8", ".trc"),
     ("bvh", "text/plain; charset=utf-8", ".bvh"), ("fhir", "application/fhir+json", "-fhir.json")],
)  # fmt: skip
def test_each_format_downloads_with_its_type_and_name(client, upload, auth_headers, fmt, media_type, file_name):
    session_id, _, therapist = upload(make_khs("squat", 2, seed=1), "squat")
    response = _export(client, session_id, fmt, auth_headers(therapist))
    assert response.status_code == 200, response.text
    assert response.headers["content-type"] == media_type
    assert response.headers["content-disposition"] == f'attachment; filename="session-{session_id}{file_name}"'


def test_csv_zip_holds_the_stored_metrics(client, upload, auth_headers):
    session_id, patient, _ = upload(make_khs("squat", 3, seed=2), "squat")
    headers = auth_headers(patient)
    stored = client.get(f"/api/v1/sessions/{session_id}", headers=headers).json()["metrics"]
    with zipfile.ZipFile(io.BytesIO(_export(client, session_id, "csv", headers).content)) as z:
        names = sorted(z.namelist())
        reps = z.read("repetitions.csv").decode().strip().splitlines()
    assert names == ["angles_filtered.csv", "angles_raw.csv", "metrics.csv", "recording.csv", "repetitions.csv"]
    assert len(reps) - 1 == stored["repetitions"] == 3


def test_fhir_bundle_names_the_patient_and_validates(client, upload, auth_headers):
    session_id, patient, therapist = upload(make_khs("elbow_flexion", 3, seed=3), "elbow_flexion")
    body = _export(client, session_id, "fhir", auth_headers(therapist)).json()
    R4B.Bundle.model_validate(body)
    observations = [e["resource"] for e in body["entry"] if e["resource"]["resourceType"] == "Observation"]
    assert observations and all(o["subject"] == {"reference": f"Patient/{patient.id}"} for o in observations)
    codes = {o["code"]["coding"][0]["code"] for o in observations}
    assert {"55411-3", "repetitions", "range-of-motion.elbow_flexion_L", "indicator.flexibility"} <= codes


def test_bvh_reproduces_the_stored_filtered_recording(client, upload, auth_headers, tmp_path):
    data = make_khs("squat", 2, seed=4)
    session_id, _, therapist = upload(data, "squat")
    path = tmp_path / "s.bvh"
    path.write_bytes(_export(client, session_id, "bvh", auth_headers(therapist)).content)
    filtered = sf.decode(data).filtered
    assert filtered is not None
    err_mm = np.linalg.norm(bvh.read(path).positions - filtered.positions, axis=-1) * 1000
    assert np.sqrt(np.mean(err_mm**2)) < 0.6, err_mm.max()


def test_exporting_is_audited_with_the_format(client, db_session, upload, auth_headers):
    session_id, _, therapist = upload(make_khs("squat", 2, seed=5), "squat")
    assert _export(client, session_id, "trc", auth_headers(therapist)).status_code == 200
    events = db_session.scalars(select(AuditEvent).where(AuditEvent.object_id == str(session_id))).all()
    exports = [e for e in events if e.action == "session.export.read"]
    assert len(exports) == 1 and exports[0].detail == {"format": "trc"}


def test_unknown_format_is_422_with_error_and_detail(client, upload, auth_headers):
    session_id, patient, _ = upload(make_khs("squat", 2, seed=6), "squat")
    response = _export(client, session_id, "xlsx", auth_headers(patient))
    assert response.status_code == 422
    body = response.json()
    assert set(body) == {"error", "detail"} and "format" in body["detail"]


def test_missing_format_is_422(client, upload, auth_headers):
    session_id, patient, _ = upload(make_khs("squat", 2, seed=6), "squat")
    response = client.get(f"/api/v1/sessions/{session_id}/export", headers=auth_headers(patient))
    assert response.status_code == 422 and "format" in response.json()["detail"]


@pytest.mark.parametrize("role", ["patient", "therapist"])
def test_a_session_of_someone_else_is_404(client, upload, make_user, auth_headers, role):
    session_id, _, _ = upload(make_khs("squat", 2, seed=7), "squat")
    response = _export(client, session_id, "csv", auth_headers(make_user(role)))
    assert response.status_code == 404
    assert response.json() == {"error": "SessionNotFound", "detail": f"session {session_id} does not exist"}


def test_anonymous_gets_401(client, upload):
    session_id, _, _ = upload(make_khs("squat", 2, seed=8), "squat")
    assert _export(client, session_id, "csv", {}).status_code == 401


def test_openapi_documents_the_download_types_and_errors(client):
    op = client.get("/openapi.json").json()["paths"]["/api/v1/sessions/{session_id}/export"]["get"]
    assert set(op["responses"]["200"]["content"]) == {"application/zip", "text/plain", "application/fhir+json"}
    assert {"400", "401", "404", "409", "422"} <= set(op["responses"])
    param = next(p for p in op["parameters"] if p["name"] == "format")
    assert param["required"] is True and param["schema"]["enum"] == ["csv", "trc", "bvh", "fhir"]
    assert json.dumps(op["responses"]["404"]).count("SessionNotFound") >= 1


def test_a_session_without_stored_metrics_is_analysed_again(client, db_session, store, make_patient_with_therapist,
                                                            auth_headers):  # fmt: skip
    patient, therapist = make_patient_with_therapist()
    squat = db_session.scalar(select(Exercise).where(Exercise.slug == "squat"))
    row = store(patient, squat, T0, data=make_khs("squat", 3, seed=11), metrics=False)
    body = _export(client, row.id, "fhir", auth_headers(therapist)).json()
    observations = [e["resource"] for e in body["entry"] if e["resource"]["resourceType"] == "Observation"]
    reps = [o for o in observations if o["code"]["coding"][0]["code"] == "repetitions"]
    assert reps[0]["valueQuantity"]["value"] == 3


def test_fhir_without_any_metrics_is_409(client, db_session, store, make_patient_with_therapist, auth_headers):
    patient, therapist = make_patient_with_therapist()
    unknown = Exercise(slug="not_in_library", name="N", instructions="-", defining_angles=["knee_flexion_L"],
                       plane="sagittal", normal_range_min_deg=0.0, normal_range_max_deg=90.0,
                       pose="standing")  # fmt: skip
    db_session.add(unknown)
    db_session.flush()
    row = store(patient, unknown, T0, data=make_khs("squat", 2, seed=12), metrics=False)
    headers = auth_headers(therapist)
    assert _export(client, row.id, "trc", headers).status_code == 200, "trc needs no metrics"
    response = _export(client, row.id, "fhir", headers)  # last: an error rolls the test's data back
    assert response.status_code == 409, response.text
    assert response.json()["error"] == "ExportUnavailable" and "analysis document" in response.json()["detail"]


def test_corrupt_stored_file_is_a_typed_400(client, store, make_patient_with_therapist, auth_headers, exercise):
    patient, therapist = make_patient_with_therapist()
    data = bytearray(make_khs("squat", 2, seed=13))
    data[100] ^= 0xFF
    row = store(patient, exercise, T0, data=bytes(data), metrics=False)
    response = _export(client, row.id, "bvh", auth_headers(therapist))
    assert response.status_code == 400 and response.json()["error"] == "InvalidSessionFile"
    assert "checksum_mismatch" in response.json()["detail"]


def _answer(client, session_id: int, patient_headers: dict[str, Any], pain, effort) -> None:
    r = client.put(f"/api/v1/sessions/{session_id}/feeling", json={"pain": pain, "effort": effort},
                   headers=patient_headers)  # fmt: skip
    assert r.status_code == 200, r.text


def test_csv_zip_holds_how_the_set_felt(client, upload, auth_headers):
    session_id, patient, therapist = upload(make_khs("squat", 3, seed=2), "squat")
    _answer(client, session_id, auth_headers(patient), 6, 3.5)
    with zipfile.ZipFile(io.BytesIO(_export(client, session_id, "csv", auth_headers(therapist)).content)) as z:
        rows = z.read("feeling.csv").decode().splitlines()
    assert rows[0] == "pain_nrs,effort_borg_cr10,answered_at", rows
    pain, effort, answered = rows[1].split(",")
    assert (pain, effort) == ("6", "3.5") and answered.endswith("Z"), rows


def test_csv_zip_has_no_feeling_table_before_the_patient_answers(client, upload, auth_headers):
    session_id, _, therapist = upload(make_khs("squat", 2, seed=4), "squat")
    with zipfile.ZipFile(io.BytesIO(_export(client, session_id, "csv", auth_headers(therapist)).content)) as z:
        assert "feeling.csv" not in z.namelist()


def test_fhir_bundle_says_pain_with_its_loinc_code_and_effort_on_the_borg_scale(client, upload, auth_headers):
    session_id, patient, therapist = upload(make_khs("elbow_flexion", 3, seed=3), "elbow_flexion")
    _answer(client, session_id, auth_headers(patient), 7, 4.5)
    body = _export(client, session_id, "fhir", auth_headers(therapist)).json()
    R4B.Bundle.model_validate(body)
    surveys = [e["resource"] for e in body["entry"] if e["resource"]["resourceType"] == "Observation"
               and e["resource"]["category"][0]["coding"][0]["code"] == "survey"]  # fmt: skip
    by_code = {o["code"]["coding"][0]["code"]: o for o in surveys}
    assert set(by_code) == {"72514-3", "effort-borg-cr10"}, by_code
    pain, effort = by_code["72514-3"], by_code["effort-borg-cr10"]
    assert pain["code"]["coding"][0] == {
        "system": "http://loinc.org",
        "code": "72514-3",
        "display": "Pain severity - 0-10 verbal numeric rating [Score] - Reported",
    }
    assert pain["valueQuantity"]["value"] == 7 and pain["valueQuantity"]["code"] == "{score}"
    assert effort["code"]["coding"][0]["system"] == "https://kinect-home-coach.example/fhir/CodeSystem/patient-reported"
    assert effort["valueQuantity"]["value"] == 4.5 and "Borg CR10" in effort["method"]["text"]
    for o in (pain, effort):
        assert o["subject"] == o["performer"][0] == {"reference": f"Patient/{patient.id}"} and "device" not in o
        assert o["issued"].endswith("Z")


def test_fhir_bundle_leaves_out_a_skipped_question(client, upload, auth_headers):
    session_id, patient, therapist = upload(make_khs("elbow_flexion", 3, seed=5), "elbow_flexion")
    _answer(client, session_id, auth_headers(patient), None, 2.0)
    body = _export(client, session_id, "fhir", auth_headers(therapist)).json()
    codes = [e["resource"]["code"]["coding"][0]["code"] for e in body["entry"] if "code" in e["resource"]]
    assert "effort-borg-cr10" in codes and "72514-3" not in codes
