"""The live loop's API: the agent's presence, Start and Stop for the patient, the agent's progress to the pages."""

from __future__ import annotations

import datetime as dt
import uuid
from typing import Any

import pytest

from backend.database import utcnow
from backend.live import progress_gate, service


def _connect(db_session, device, seen_ago_s=0.0):
    device.live_stream_id = str(uuid.uuid4())
    device.last_seen_at = utcnow() - dt.timedelta(seconds=seen_ago_s)
    db_session.flush()


def test_status_says_unpaired_offline_then_online(client, db_session, home, make_user, auth_headers):
    lonely = make_user("patient")
    lonely_hdr = auth_headers(lonely)
    assert client.get("/api/v1/live/status", headers=lonely_hdr).json()["state"] == "unpaired"
    url = f"/api/v1/live/status?patient_id={home['patient'].id}"
    assert client.get(url, headers=home["therapist_hdr"]).json()["state"] == "offline"
    _connect(db_session, home["device"])
    body = client.get(url, headers=home["therapist_hdr"]).json()
    assert body["state"] == "online" and body["device_id"] == home["device"].id, body


def test_a_device_not_heard_from_for_a_while_is_offline(client, db_session, home):
    _connect(db_session, home["device"], seen_ago_s=service.STALE_S + 5)  # e.g. its server worker died
    assert client.get("/api/v1/live/status", headers=home["patient_hdr"]).json()["state"] == "offline"


def test_the_agent_stream_marks_the_device_online_and_offline_when_it_ends(client, db_session, home, events):
    response = client.get("/api/v1/live/agent", headers=home["device_hdr"])  # test settings: ends at once, no grace
    assert response.status_code == 200 and response.headers["content-type"].startswith("text/event-stream")
    kinds = [(ev.kind, ev.data["online"]) for ev in events]
    assert kinds == [("live.agent", True), ("live.agent", False)], kinds
    db_session.refresh(home["device"])
    assert home["device"].live_stream_id is None


def test_a_replaced_stream_does_not_announce_offline(db_session, home, events):
    first = service.connect(db_session=db_session, device=home["device"])
    second = service.connect(db_session=db_session, device=home["device"])  # the agent reconnected
    assert not service.disconnect(db_session=db_session, device_id=home["device"].id, stream_id=first)
    assert not service.heartbeat(db_session=db_session, device_id=home["device"].id, stream_id=first)
    assert service.heartbeat(db_session=db_session, device_id=home["device"].id, stream_id=second)
    assert [ev.data["online"] for ev in events] == [True, True]


def test_a_revoked_device_loses_its_stream_at_the_next_heartbeat(db_session, home):
    stream = service.connect(db_session=db_session, device=home["device"])
    home["device"].revoked_at = utcnow()
    db_session.flush()
    assert not service.heartbeat(db_session=db_session, device_id=home["device"].id, stream_id=stream)


def test_start_while_the_agent_is_offline_is_409_in_plain_words(client, home, events):
    r = client.post("/api/v1/live/start", json={"plan_item_id": home["item"].id}, headers=home["patient_hdr"])
    assert r.status_code == 409 and r.json()["error"] == "AgentOffline", r.text
    assert "home computer is not connected" in r.json()["detail"]
    assert events == []


def test_start_sends_the_exercise_target_and_angles_to_the_connected_device(client, db_session, home, exercise, events):
    _connect(db_session, home["device"])
    r = client.post("/api/v1/live/start", json={"plan_item_id": home["item"].id}, headers=home["patient_hdr"])
    assert r.status_code == 202, r.text
    out = r.json()
    assert out["device_id"] == home["device"].id and out["target_reps"] == 8 and out["exercise_slug"] == exercise.slug
    (ev,) = events
    assert ev.kind == "live.command" and ev.patient_id == home["patient"].id
    assert ev.data["action"] == "start" and ev.data["set_id"] == out["set_id"]
    assert ev.data["angles"] == list(exercise.defining_angles) and ev.data["plan_item_id"] == home["item"].id


def test_therapists_may_not_start_a_patients_set(client, db_session, home):
    _connect(db_session, home["device"])
    r = client.post("/api/v1/live/start", json={"plan_item_id": home["item"].id}, headers=home["therapist_hdr"])
    assert r.status_code == 403 and "only patients" in r.json()["detail"]


def test_another_patients_plan_item_is_404(client, db_session, home, make_user, auth_headers):
    _connect(db_session, home["device"])
    r = client.post(
        "/api/v1/live/start", json={"plan_item_id": home["item"].id}, headers=auth_headers(make_user("patient"))
    )
    assert r.status_code == 404 and r.json()["error"] == "PlanNotFound"


def test_a_bad_plan_item_id_is_422(client, home):
    r = client.post("/api/v1/live/start", json={"plan_item_id": 0}, headers=home["patient_hdr"])
    assert r.status_code == 422 and "plan_item_id" in r.json()["detail"]


def test_stop_goes_to_every_device_of_the_patient(client, home, events):
    set_id = str(uuid.uuid4())
    r = client.post("/api/v1/live/stop", json={"set_id": set_id}, headers=home["patient_hdr"])
    assert r.status_code == 202, r.text
    assert [(ev.kind, ev.data["action"], ev.data["set_id"], ev.data["device_id"]) for ev in events] == [
        ("live.command", "stop", set_id, None)
    ]
    r = client.post("/api/v1/live/stop", json={"set_id": "not-a-uuid"}, headers=home["patient_hdr"])
    assert r.status_code == 422 and "set_id" in r.json()["detail"]


def _started(db_session, device) -> str:
    """Returns a set id the server started on the device (as Start does; test_live_set_guard.py covers Start)."""
    device.live_set_id = str(uuid.uuid4())
    db_session.flush()
    return device.live_set_id


def test_progress_reaches_the_patient_and_names_its_device(client, db_session, home, events):
    msg: dict[str, Any] = {
        "set_id": _started(db_session, home["device"]),
        "exercise_slug": "squat",
        "state": "recording",
    }
    msg |= {"count": 3, "target": 8}
    msg |= {"angle_name": "knee_flexion_L", "angle_deg": 87.5, "hint": "Step back a little", "sent_at": 1.8e9}
    r = client.post("/api/v1/live/progress", json=msg, headers=home["device_hdr"])
    assert r.status_code == 204, r.text
    (ev,) = events
    assert ev.kind == "live.progress" and ev.patient_id == home["patient"].id
    assert ev.data["device_id"] == home["device"].id and ev.data["count"] == 3 and ev.data["hint"] == msg["hint"]


def test_a_starting_message_reaches_the_patient(client, db_session, home, events):
    """The agent's answer to Start before its first count (kinect_agent.live.set_recorder)."""
    msg = {"set_id": _started(db_session, home["device"]), "exercise_slug": "squat", "state": "starting", "count": 0}
    r = client.post("/api/v1/live/progress", json=msg, headers=home["device_hdr"])
    assert r.status_code == 204, r.text
    (ev,) = events
    assert ev.kind == "live.progress" and ev.data["state"] == "starting" and ev.data["set_id"] == msg["set_id"]


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"count": -1}, "count"),
        ({"state": "dancing"}, "state"),
        ({"set_id": "x"}, "set_id"),
        ({"hint": "x" * 201}, "hint"),
        ({"extra": 1}, "extra"),
        ({"reason": "bored"}, "reason"),
    ],
)
def test_bad_progress_is_422_naming_the_field(client, home, events, change, field):
    msg = {"set_id": str(uuid.uuid4()), "exercise_slug": "squat", "state": "recording", "count": 3} | change
    r = client.post("/api/v1/live/progress", json=msg, headers=home["device_hdr"])
    assert r.status_code == 422 and field in r.json()["detail"], r.text
    assert events == []


def test_non_finite_angle_is_refused(client, home):
    body = (
        f'{{"set_id": "{uuid.uuid4()}", "exercise_slug": "squat", "state": "recording", "count": 1, "angle_deg": NaN}}'
    )
    r = client.post(
        "/api/v1/live/progress", content=body, headers=home["device_hdr"] | {"Content-Type": "application/json"}
    )
    assert r.status_code == 422, r.text


def test_users_may_not_post_progress(client, home):
    msg = {"set_id": str(uuid.uuid4()), "exercise_slug": "squat", "state": "recording", "count": 3}
    assert client.post("/api/v1/live/progress", json=msg, headers=home["patient_hdr"]).status_code == 403


def test_devices_may_not_start(client, home):
    r = client.post("/api/v1/live/start", json={"plan_item_id": home["item"].id}, headers=home["device_hdr"])
    assert r.status_code == 403


def test_a_flood_of_progress_is_answered_429_and_a_repeat_is_not_published(client, db_session, home, events):
    set_id = _started(db_session, home["device"])
    statuses = []
    for i in range(3 * progress_gate.MAX_PER_WINDOW):
        msg = {"set_id": set_id, "exercise_slug": "squat", "state": "recording", "count": i}
        statuses.append(client.post("/api/v1/live/progress", json=msg, headers=home["device_hdr"]).status_code)
    assert statuses.count(204) <= 2 * progress_gate.MAX_PER_WINDOW and 429 in statuses, statuses
    before = len(events)
    end = {"set_id": set_id, "exercise_slug": "squat", "state": "ended", "count": 5}
    assert client.post("/api/v1/live/progress", json=end, headers=home["device_hdr"]).status_code == 204
    assert client.post("/api/v1/live/progress", json=end, headers=home["device_hdr"]).status_code == 204
    assert len(events) == before + 1, "the identical message twice is passed on once"
