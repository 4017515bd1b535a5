"""Live progress is accepted only for the set the server started for the posting device (issue 27, finding 8):
a set id the server never sent to that device is 409 LiveSetUnknown naming the set, and nothing reaches the
patient's pages."""

from __future__ import annotations

import uuid
from typing import Any

from backend.database import utcnow


def _recording(set_id: str, count: int = 1) -> dict[str, Any]:
    return {"set_id": set_id, "exercise_slug": "squat", "state": "recording", "count": count, "target": 8}


def _start(client, db_session, home) -> str:
    """Connects the home's device and presses Start as the patient; returns the set id the server made."""
    home["device"].live_stream_id = str(uuid.uuid4())
    home["device"].last_seen_at = utcnow()
    db_session.flush()
    r = client.post("/api/v1/live/start", json={"plan_item_id": home["item"].id}, headers=home["patient_hdr"])
    assert r.status_code == 202, r.text
    return r.json()["set_id"]


def test_progress_for_a_set_the_server_never_started_is_409_and_not_shown(client, home, events):
    invented = str(uuid.uuid4())
    r = client.post("/api/v1/live/progress", json=_recording(invented), headers=home["device_hdr"])
    assert r.status_code == 409, r.text
    body = r.json()
    assert body["error"] == "LiveSetUnknown" and invented in body["detail"], body
    assert [ev for ev in events if ev.kind == "live.progress"] == []


def test_progress_for_the_started_set_reaches_the_patient(client, db_session, home, events):
    set_id = _start(client, db_session, home)
    r = client.post("/api/v1/live/progress", json=_recording(set_id), headers=home["device_hdr"])
    assert r.status_code == 204, r.text
    (ev,) = [ev for ev in events if ev.kind == "live.progress"]
    assert ev.data["set_id"] == set_id and ev.data["device_id"] == home["device"].id
    end = _recording(set_id, 8) | {"state": "ended", "reason": "target"}
    assert client.post("/api/v1/live/progress", json=end, headers=home["device_hdr"]).status_code == 204


def test_the_started_set_is_stored_with_the_device(client, db_session, home):
    """Kept in the database, so every server worker knows it (the agent's posts may reach any of them)."""
    set_id = _start(client, db_session, home)
    db_session.expire_all()
    db_session.refresh(home["device"])
    assert home["device"].live_set_id == set_id


def test_another_device_may_not_post_for_the_started_set(client, db_session, home, device_headers, events):
    set_id = _start(client, db_session, home)
    _, other_hdr = device_headers(home["patient"])  # a second paired device of the same patient
    r = client.post("/api/v1/live/progress", json=_recording(set_id), headers=other_hdr)
    assert r.status_code == 409 and set_id in r.json()["detail"], r.text
    assert [ev for ev in events if ev.kind == "live.progress"] == []


def test_a_new_start_replaces_the_devices_set(client, db_session, home, events):
    first = _start(client, db_session, home)
    second = _start(client, db_session, home)
    assert first != second
    assert client.post("/api/v1/live/progress", json=_recording(first), headers=home["device_hdr"]).status_code == 409
    assert client.post("/api/v1/live/progress", json=_recording(second), headers=home["device_hdr"]).status_code == 204
