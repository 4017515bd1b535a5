"""GET /api/v1/sessions (list, filters, paging), /sessions/{id} and /sessions/{id}/file: content and access."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import select

from backend.audit.models import AuditEvent
from backend.suggestions.models import Suggestion

T0 = dt.datetime(2026, 11, 2, 9, 0, tzinfo=dt.UTC)  # a Monday


def test_list_is_newest_first_with_metric_scalars(client, make_user, auth_headers, exercise, store):
    patient = make_user("patient")
    old = store(patient, exercise, T0, reps=8, rom=80.0)
    new = store(patient, exercise, T0 + dt.timedelta(days=1), reps=12, rom=95.5)
    response = client.get("/api/v1/sessions", headers=auth_headers(patient), params={"patient_id": patient.id})
    assert response.status_code == 200, response.text
    body = response.json()
    assert body["total"] == 2
    assert [i["id"] for i in body["items"]] == [new.id, old.id]
    assert (body["items"][0]["repetitions"], body["items"][0]["rom_deg"]) == (12, 95.5)
    assert body["items"][0]["exercise_slug"] == exercise.slug
    assert "metrics" not in body["items"][0]


def test_list_filters_by_exercise_and_since(client, make_user, auth_headers, exercise, other_exercise, store):
    patient = make_user("patient")
    store(patient, exercise, T0)
    wanted = store(patient, exercise, T0 + dt.timedelta(days=3))
    store(patient, other_exercise, T0 + dt.timedelta(days=4))
    params = {"patient_id": patient.id, "exercise": exercise.slug, "since": "2026-11-04T00:00:00Z"}
    body = client.get("/api/v1/sessions", headers=auth_headers(patient), params=params).json()
    assert [i["id"] for i in body["items"]] == [wanted.id]


def test_list_pages(client, make_user, auth_headers, exercise, store):
    patient = make_user("patient")
    rows = [store(patient, exercise, T0 + dt.timedelta(hours=h)) for h in range(5)]
    params = {"patient_id": patient.id, "limit": 2, "offset": 2}
    body = client.get("/api/v1/sessions", headers=auth_headers(patient), params=params).json()
    assert body["total"] == 5
    assert [i["id"] for i in body["items"]] == [rows[2].id, rows[1].id]


def test_list_without_patient_shows_only_what_the_caller_may_see(
    client, make_user, make_patient_with_therapist, auth_headers, exercise, store
):
    mine, therapist = make_patient_with_therapist()
    stranger = make_user("patient")
    own_row = store(mine, exercise, T0)
    store(stranger, exercise, T0)
    for caller in (mine, therapist):
        ids = [i["id"] for i in client.get("/api/v1/sessions", headers=auth_headers(caller)).json()["items"]]
        assert ids == [own_row.id]


def test_list_of_another_patient_is_404(client, make_user, auth_headers):
    patient, other = make_user("patient"), make_user("patient")
    response = client.get("/api/v1/sessions", headers=auth_headers(patient), params={"patient_id": other.id})
    assert response.status_code == 404, response.text


def test_list_with_unknown_exercise_is_404(client, make_user, auth_headers):
    patient = make_user("patient")
    response = client.get("/api/v1/sessions", headers=auth_headers(patient), params={"exercise": "juggling"})
    assert response.status_code == 404, response.text
    assert response.json()["detail"] == "exercise 'juggling' does not exist"


def test_detail_has_metrics_and_suggestions_by_viewer(
    client, db_session, make_patient_with_therapist, auth_headers, exercise, store
):
    patient, therapist = make_patient_with_therapist()
    row = store(patient, exercise, T0, reps=7)
    db_session.add_all(
        [
            Suggestion(patient_id=patient.id, session_id=row.id, source="system", rule="too_fast", text="a"),
            Suggestion(
                patient_id=patient.id,
                session_id=row.id,
                source="system",
                rule="fewer_reps",
                text="b",
                status="approved",
            ),
        ]
    )
    db_session.flush()
    as_therapist = client.get(f"/api/v1/sessions/{row.id}", headers=auth_headers(therapist)).json()
    as_patient = client.get(f"/api/v1/sessions/{row.id}", headers=auth_headers(patient)).json()
    assert as_therapist["metrics"]["repetitions"] == 7
    assert sorted(s["rule"] for s in as_therapist["suggestions"]) == ["fewer_reps", "too_fast"]
    assert [s["rule"] for s in as_patient["suggestions"]] == ["fewer_reps"]


def test_detail_of_unknown_session_is_404(client, make_user, auth_headers):
    response = client.get("/api/v1/sessions/999999", headers=auth_headers(make_user("admin")))
    assert response.status_code == 404, response.text
    assert response.json() == {"error": "SessionNotFound", "detail": "session 999999 does not exist"}


def test_detail_of_another_patients_session_is_404(client, db_session, make_user, auth_headers, exercise, store):
    owner, other = make_user("patient"), make_user("patient")
    row = store(owner, exercise, T0)
    headers = auth_headers(other)
    db_session.commit()  # a refused request rolls back; keep the setup out of its reach
    assert client.get(f"/api/v1/sessions/{row.id}", headers=headers).status_code == 404
    assert client.get(f"/api/v1/sessions/{row.id}/file", headers=headers).status_code == 404


def test_file_returns_the_stored_bytes(client, make_user, auth_headers, exercise, store):
    patient = make_user("patient")
    row = store(patient, exercise, T0, data=b"\x89KHS stored bytes")
    response = client.get(f"/api/v1/sessions/{row.id}/file", headers=auth_headers(patient))
    assert response.status_code == 200, response.text
    assert response.content == b"\x89KHS stored bytes"
    assert response.headers["content-type"] == "application/octet-stream"


def test_reads_are_audited(client, db_session, make_user, auth_headers, exercise, store):
    patient = make_user("patient")
    row = store(patient, exercise, T0)
    headers = auth_headers(patient)
    client.get("/api/v1/sessions", headers=headers)
    client.get(f"/api/v1/sessions/{row.id}", headers=headers)
    client.get(f"/api/v1/sessions/{row.id}/file", headers=headers)
    actions = db_session.scalars(select(AuditEvent.action).where(AuditEvent.patient_id == patient.id)).all()
    assert sorted(actions) == ["session.file.read", "session.list", "session.read"]
