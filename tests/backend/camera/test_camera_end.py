"""A camera set from batches to the stored session: the live count rises with squats (the online filter on the
mapped landmarks), the end stores one session of device `webcam` through the offline pipeline, and a repeated end,
re-sent batches or a rebuilt live state never count or store twice."""

from __future__ import annotations

import uuid
from typing import Any

from sqlalchemy import func, select

from backend.camera import live_count
from backend.camera.models import CameraBatch
from backend.sessions.metrics import json_ready
from backend.sessions.models import ExerciseSession
from backend.sessions.service import session_file as stored_file
from kinect_agent.formats import session_file
from kinect_agent.processing.config import config_for_device
from tests.backend.camera.landmarks import batch, squats

PER_BATCH = 6  # frames per batch: 0.2 s at 30 fps


def _send_all(client, set_id, frames, headers) -> list[dict[str, Any]]:
    answers = []
    for seq, k in enumerate(range(0, len(frames), PER_BATCH)):
        r = client.post(f"/api/v1/camera/sets/{set_id}/batches", json=batch(seq, frames[k : k + PER_BATCH]),
                        headers=headers)  # fmt: skip
        assert r.status_code == 201, r.text
        answers.append(r.json())
    return answers


def _sessions(db_session, patient_id) -> int:
    return db_session.scalar(
        select(func.count()).select_from(ExerciseSession).where(ExerciseSession.patient_id == patient_id)
    )


def _batches(db_session, set_id) -> int:
    return db_session.scalar(
        select(func.count()).select_from(CameraBatch).where(CameraBatch.set_id == uuid.UUID(set_id))
    )


def test_squats_count_live_and_the_end_stores_one_webcam_session(client, db_session, camera_home, started, monkeypatch):
    events = []
    monkeypatch.setattr("backend.camera.live_count.publish", lambda _s, ev: events.append(ev))
    set_id, h = started(seconds_ago=120), camera_home["headers"]
    answers = _send_all(client, set_id, squats(3), h)
    counts = [a["count"] for a in answers]
    assert counts == sorted(counts) and counts[-1] == 3, counts
    assert [e.kind for e in events] == ["live.progress"] * len(answers)
    assert events[-1].data["count"] == 3 and events[-1].data["device"] == "webcam"
    r = client.post(f"/api/v1/camera/sets/{set_id}/end", json={"last_seq": len(answers) - 1, "reason": "target"},
                    headers=h)  # fmt: skip
    assert r.status_code == 200 and r.json()["status"] == "stored", r.text
    session_id = r.json()["session_id"]
    stored = db_session.get(ExerciseSession, session_id)
    assert stored.client_session_id == uuid.UUID(set_id) and stored.device_id is None
    payload = session_file.decode(stored_file(db_session=db_session, session_id=session_id))
    assert payload.raw.meta.device == "webcam" and payload.filtered is not None
    assert payload.params["config"] == json_ready(config_for_device("webcam").model_dump())  # the webcam's settings
    assert payload.params["model"]["name"] == "pose_landmarker_lite.task"
    webcam = payload.raw.meta.extra["webcam"]  # the header the agent's webcam source writes too
    assert webcam["model"] == payload.params["model"] and webcam["runtime"].startswith("@mediapipe/tasks-vision")
    assert webcam["image_size"] == [640, 480] and webcam["images"] == payload.raw.n_frames
    assert len(payload.params["model"]["sha256"]) == 64
    assert 29 <= payload.params["fps_achieved"] <= 31, payload.params["fps_achieved"]
    detail = client.get(f"/api/v1/sessions/{session_id}", headers=h).json()
    assert detail["repetitions"] == 3, detail
    assert _batches(db_session, set_id) == 0  # the landmarks live on only as the session's skeleton
    # the same end again (a lost answer), and a batch sent again after the end: nothing new
    again = client.post(f"/api/v1/camera/sets/{set_id}/end", json={"last_seq": len(answers) - 1}, headers=h)
    assert again.status_code == 200 and again.json()["session_id"] == session_id, again.text
    resent = client.post(f"/api/v1/camera/sets/{set_id}/batches", json=batch(0, squats(3)[:PER_BATCH]), headers=h)
    assert resent.status_code == 200 and resent.json()["repeated"] is True, resent.text
    late = client.post(f"/api/v1/camera/sets/{set_id}/batches", json=batch(len(answers), squats(1, t0=200)[:3]),
                       headers=h)  # fmt: skip
    assert late.status_code == 409 and late.json()["error"] == "CameraSetEnded", late.text
    assert _sessions(db_session, camera_home["patient"].id) == 1


def test_a_lost_live_state_is_rebuilt_from_the_stored_batches_with_the_same_count(client, camera_home, started):
    set_id, h = started(seconds_ago=120), camera_home["headers"]
    frames = squats(2)
    half = len(frames) // 2 // PER_BATCH * PER_BATCH
    _send_all(client, set_id, frames[:half], h)
    live_count.forget(uuid.UUID(set_id))  # another worker, or a restart
    seq = half // PER_BATCH
    last = None
    for k in range(half, len(frames), PER_BATCH):
        r = client.post(f"/api/v1/camera/sets/{set_id}/batches", json=batch(seq, frames[k : k + PER_BATCH]), headers=h)
        assert r.status_code == 201, r.text
        last, seq = r.json(), seq + 1
    assert last is not None and last["count"] == 2, last


def test_the_end_waits_for_batches_the_page_sent_and_a_too_short_set_stores_nothing(client, db_session, camera_home,
                                                                                    started):  # fmt: skip
    set_id, h = started(), camera_home["headers"]
    r = client.post(f"/api/v1/camera/sets/{set_id}/batches", json=batch(0, squats(1)[:5]), headers=h)
    assert r.status_code == 201, r.text
    r = client.post(f"/api/v1/camera/sets/{set_id}/end", json={"last_seq": 3}, headers=h)
    assert r.status_code == 409 and "batches 1..3" in r.json()["detail"], r.text
    r = client.post(f"/api/v1/camera/sets/{set_id}/end", json={"last_seq": 0}, headers=h)
    assert r.status_code == 200 and r.json()["status"] == "failed" and "frames" in r.json()["error"], r.text
    assert r.json()["failure"] == "too_short", r.text
    assert _sessions(db_session, camera_home["patient"].id) == 0
    assert _batches(db_session, set_id) == 0


def test_a_set_whose_frames_make_no_storable_session_ends_failed(client, db_session, camera_home, started, settings,
                                                                  monkeypatch):  # fmt: skip
    """Frames no session file may hold (here more than the server's frame limit) end the set failed, with the reason,
    once: the same frames would fail the same way on every retry (it was an error the page retried for ever)."""
    set_id, h = started(seconds_ago=120), camera_home["headers"]
    answers = _send_all(client, set_id, squats(3), h)
    monkeypatch.setattr(settings, "SESSION_MAX_FRAMES", 50)
    r = client.post(f"/api/v1/camera/sets/{set_id}/end", json={"last_seq": len(answers) - 1, "reason": "stop"},
                    headers=h)  # fmt: skip
    out = r.json()
    assert r.status_code == 200 and (out["status"], out["failure"]) == ("failed", "not_storable"), r.text
    assert "could not be stored" in out["error"] and "the limit is 50" in out["error"], out["error"]
    assert _sessions(db_session, camera_home["patient"].id) == 0 and _batches(db_session, set_id) == 0
    r = client.post(f"/api/v1/camera/sets/{set_id}/end", json={"last_seq": len(answers) - 1, "reason": "stop"},
                    headers=h)  # fmt: skip
    assert r.status_code == 200 and r.json() == out, r.text


def test_a_failing_live_count_does_not_lose_the_batch(client, db_session, camera_home, started, monkeypatch):
    def broken(*_args, **_kw):
        raise ValueError("the live count broke")

    monkeypatch.setattr("kinect_agent.analysis.live.LiveCount.add", broken)
    set_id, h = started(), camera_home["headers"]
    r = client.post(f"/api/v1/camera/sets/{set_id}/batches", json=batch(0, squats(1)[:PER_BATCH]), headers=h)
    assert r.status_code == 201 and r.json()["count"] == 0 and r.json()["n_frames"] == PER_BATCH, r.text


def test_a_set_with_minutes_out_of_the_picture_is_stored_at_the_camera_rate(client, db_session, camera_home, started):
    """Squats at 10 frames a second, then 4 minutes with no frame (the patient out of the picture, the page hidden),
    then more squats: 160 frames over 250 s, 0.6 a second on average, which no recording may claim as its rate. The
    set is stored with the camera's rate, 10 Hz, and the gap stays a gap in the frame times."""
    set_id, h = started(seconds_ago=400), camera_home["headers"]
    frames = squats(2, fps=10.0) + squats(2, fps=10.0, t0=250.0)
    answers = _send_all(client, set_id, frames, h)
    r = client.post(f"/api/v1/camera/sets/{set_id}/end", json={"last_seq": len(answers) - 1, "reason": "stop"},
                    headers=h)  # fmt: skip
    assert r.status_code == 200 and r.json()["status"] == "stored", r.text
    payload = session_file.decode(stored_file(db_session=db_session, session_id=r.json()["session_id"]))
    assert payload.raw.meta.rate_hz == 10.0 and payload.params["fps_achieved"] == 10.0, payload.raw.meta
    assert payload.raw.n_frames == len(frames)
    assert _sessions(db_session, camera_home["patient"].id) == 1


def test_frames_a_millisecond_apart_are_stored(client, db_session, camera_home, started):
    """The page stamps frames on a millisecond clock (times rounded to 0.001 s), so two frames may be 0.001 s apart;
    a file's times are sums of float64 steps, which make half of such steps 0.000999... s. The set is stored, with
    every frame (a whole run lost a set to this: "frames 0.001 s apart; a camera gives at least 0.001 s")."""
    set_id, h = started(seconds_ago=120), camera_home["headers"]
    frames = [{**f, "t": round(f["t"], 3)} for f in squats(2)]  # as the page stamps them
    for k in range(5, len(frames) - 1, 7):  # the next frame 1 ms after this one, at times 5.123 -> 5.124 etc.
        frames[k + 1] = {**frames[k + 1], "t": round(frames[k]["t"] + 0.001, 3)}
    steps = [round(b["t"] - a["t"], 6) for a, b in zip(frames, frames[1:], strict=False)]
    assert min(steps) == 0.001 and any(b["t"] - a["t"] < 0.001 for a, b in zip(frames, frames[1:], strict=False))
    answers = _send_all(client, set_id, frames, h)
    r = client.post(f"/api/v1/camera/sets/{set_id}/end", json={"last_seq": len(answers) - 1, "reason": "stop"},
                    headers=h)  # fmt: skip
    assert r.status_code == 200 and r.json()["status"] == "stored", r.text
    payload = session_file.decode(stored_file(db_session=db_session, session_id=r.json()["session_id"]))
    assert payload.raw.n_frames == len(frames)
