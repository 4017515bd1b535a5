"""GET /api/v1/sessions/{id}/replay: the session's viser recording, built once and kept for every worker."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import func, select

from backend.audit.models import AuditEvent
from backend.replay import scene
from backend.replay.models import SessionReplay
from backend.storage import get_store
from tests.backend.khs_files import make_khs
from tests.backend.replay.viser_file import node_points, read_viser

T0 = dt.datetime(2026, 11, 2, 9, 0, tzinfo=dt.UTC)


def test_therapist_and_patient_get_the_recording_built_once(
    client, make_patient_with_therapist, auth_headers, exercise, store, db_session
):
    patient, therapist = make_patient_with_therapist()
    row = store(patient, exercise, T0, data=make_khs("squat", 2, seed=21))
    first = client.get(f"/api/v1/sessions/{row.id}/replay", headers=auth_headers(therapist))
    assert first.status_code == 200, first.text
    assert first.headers["content-type"] == "application/octet-stream"
    doc = read_viser(first.content)
    assert doc["durationSeconds"] > 1.0 and node_points(doc, "/filtered/joints") and node_points(doc, "/raw/joints")
    stored = db_session.scalar(select(SessionReplay).where(SessionReplay.session_id == row.id))
    assert stored is not None and stored.version == scene.VERSION and stored.size == len(first.content)
    again = client.get(f"/api/v1/sessions/{row.id}/replay", headers=auth_headers(patient))
    assert again.status_code == 200 and again.content == first.content
    assert db_session.scalar(select(func.count()).select_from(SessionReplay)) == 1
    actions = db_session.scalars(select(AuditEvent.action).where(AuditEvent.object_id == str(row.id))).all()
    assert actions.count("session.replay.read") == 2


def test_a_recording_of_an_older_version_is_rebuilt(client, make_user, auth_headers, exercise, store, db_session):
    patient = make_user("patient")
    row = store(patient, exercise, T0, data=make_khs("squat", 2, seed=22))
    db_session.add(SessionReplay(session_id=row.id, version="replay-0", data=b"old", size=3, n_frames=1,
                                 duration_s=0.0, view="side"))  # fmt: skip
    db_session.flush()
    response = client.get(f"/api/v1/sessions/{row.id}/replay", headers=auth_headers(patient))
    assert response.status_code == 200 and response.content != b"old"
    db_session.expire_all()
    stored = db_session.scalar(select(SessionReplay).where(SessionReplay.session_id == row.id))
    assert stored.version == scene.VERSION and stored.data is None  # the recording is in the object store
    assert get_store().get(stored.data_key, stored.data_hash) == response.content


def test_no_login_is_401_and_another_patient_is_404(client, make_user, auth_headers, exercise, store):
    patient, stranger = make_user("patient"), make_user("patient")
    row = store(patient, exercise, T0, data=make_khs("squat", 1, seed=23))
    headers = auth_headers(stranger)  # made before any error response rolls the test's transaction back
    response = client.get(f"/api/v1/sessions/{row.id}/replay", headers=headers)
    assert response.status_code == 404, response.text
    response = client.get(f"/api/v1/sessions/{row.id}/replay")
    assert response.status_code == 401 and response.json()["error"] == "NotAuthenticated"


def test_missing_session_is_404(client, make_user, auth_headers):
    response = client.get("/api/v1/sessions/987654/replay", headers=auth_headers(make_user("admin")))
    assert response.status_code == 404 and response.json()["error"] == "SessionNotFound"


def test_a_stored_file_that_cannot_be_read_is_400_and_nothing_is_stored(
    client, make_user, auth_headers, exercise, store, db_session
):
    patient = make_user("patient")
    row = store(patient, exercise, T0, data=b"not a session file")
    response = client.get(f"/api/v1/sessions/{row.id}/replay", headers=auth_headers(patient))
    assert response.status_code == 400, response.text
    body = response.json()
    assert body["error"] == "InvalidSessionFile" and f"session {row.id}" in body["detail"]
    assert db_session.scalar(select(func.count()).select_from(SessionReplay)) == 0


def test_one_skeleton_alone_is_built_without_the_other_and_not_stored(
    client, make_patient_with_therapist, auth_headers, exercise, store, db_session
):
    patient, therapist = make_patient_with_therapist()
    row = store(patient, exercise, T0, data=make_khs("squat", 2, seed=22))
    headers = auth_headers(therapist)
    raw = read_viser(client.get(f"/api/v1/sessions/{row.id}/replay?layer=raw", headers=headers).content)
    assert node_points(raw, "/raw/joints") and not node_points(raw, "/filtered/joints")
    filtered = read_viser(client.get(f"/api/v1/sessions/{row.id}/replay?layer=filtered", headers=headers).content)
    assert node_points(filtered, "/filtered/joints") and not node_points(filtered, "/raw/joints")
    assert db_session.scalar(select(func.count()).select_from(SessionReplay)) == 0
    bad = client.get(f"/api/v1/sessions/{row.id}/replay?layer=both", headers=headers)
    assert bad.status_code == 422 and "layer" in bad.json()["detail"]
