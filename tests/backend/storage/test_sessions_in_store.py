"""Uploaded session files and built replays live in the object store; a lost object answers a clear error."""

from __future__ import annotations

import hashlib

from sqlalchemy import select

from backend.cli import main
from backend.replay.models import SessionReplay
from backend.sessions.models import ExerciseSession
from tests.backend.khs_files import make_khs


def test_an_upload_goes_to_the_store_and_reads_back_checked(client, db_session, upload, auth_headers, with_store,
                                                            run_jobs):  # fmt: skip
    data = make_khs("squat", 1, seed=41)
    session_id, patient, _ = upload(data, "squat")
    row = db_session.get(ExerciseSession, session_id)
    digest = hashlib.sha256(data).hexdigest()
    assert row.file_bytes is None and row.file_key == f"session/{digest[:2]}/{digest}" and row.content_hash == digest
    assert with_store.get(row.file_key, digest) == data
    response = client.get(f"/api/v1/sessions/{session_id}/file", headers=auth_headers(patient))
    assert response.status_code == 200 and response.content == data
    headers = auth_headers(patient)
    assert client.get(f"/api/v1/sessions/{session_id}/replay", headers=headers).status_code == 202
    assert run_jobs() == 1  # a worker builds the replay
    replay = client.get(f"/api/v1/sessions/{session_id}/replay", headers=headers)
    assert replay.status_code == 200
    stored = db_session.scalar(select(SessionReplay).where(SessionReplay.session_id == session_id))
    assert stored.data is None and with_store.get(stored.data_key, stored.data_hash) == replay.content


def test_a_lost_object_is_a_clear_error(client, db_session, upload, auth_headers, with_store):
    session_id, patient, _ = upload(make_khs("squat", 1, seed=42), "squat")
    headers = auth_headers(patient)
    key = db_session.get(ExerciseSession, session_id).file_key
    with_store.delete(key)
    response = client.get(f"/api/v1/sessions/{session_id}/file", headers=headers)
    assert response.status_code == 500
    body = response.json()
    assert body["error"] == "StoredObjectMissing" and body["detail"].startswith(f"stored object {key} is missing from")


def test_storage_check_command_exits_1_naming_the_lost_file(fresh_engine, with_store, monkeypatch, capsys):
    from backend.migrate import upgrade
    from tests.backend.storage.test_move import _fill_at_0010

    _fill_at_0010(fresh_engine)
    with fresh_engine.begin() as conn:
        upgrade(conn, "head")
        key = conn.scalar(select(ExerciseSession.file_key).where(ExerciseSession.id == 4))
    monkeypatch.setattr("backend.database.get_engine", lambda url=None: fresh_engine)
    assert main(["storage", "check"]) == 0
    with_store.delete(key)
    assert main(["storage", "check"]) == 1
    out = capsys.readouterr().out
    assert "6 object(s) checked, 0 missing" in out and f"missing  session 4: {key}" in out
