"""GET /api/v1/events: a server-sent-event stream, behind the login, limited to the patients the caller may see."""

from __future__ import annotations

from backend.deps import Caller
from backend.events.router import visible_patients


def test_stream_opens_as_server_sent_events(client, make_user, auth_headers):
    patient = make_user("patient")
    response = client.get("/api/v1/events", headers=auth_headers(patient))  # the test settings end streams at once
    assert response.status_code == 200, response.text
    assert response.headers["content-type"].startswith("text/event-stream")
    assert response.text.startswith("retry: 3000\n")
    assert response.headers["cache-control"] == "no-store"


def test_another_patients_stream_is_refused_and_no_login_is_401(client, make_user, auth_headers):
    patient, stranger = make_user("patient"), make_user("patient")
    headers = auth_headers(stranger)  # made before an error response rolls the test's transaction back
    response = client.get("/api/v1/events", params={"patient_id": patient.id}, headers=headers)
    assert response.status_code == 404, response.text
    assert client.get("/api/v1/events").status_code == 401


def test_each_caller_listens_to_the_patients_they_may_see(db_session, make_user, make_patient_with_therapist):
    mine, therapist = make_patient_with_therapist()
    other = make_user("patient")
    admin = make_user("admin")
    assert visible_patients(Caller(via="token", user=mine), db_session, None) == frozenset({mine.id})
    assert visible_patients(Caller(via="token", user=therapist), db_session, None) == frozenset({mine.id})
    assert visible_patients(Caller(via="token", user=admin), db_session, None) is None
    assert visible_patients(Caller(via="token", user=admin), db_session, other.id) == frozenset({other.id})
