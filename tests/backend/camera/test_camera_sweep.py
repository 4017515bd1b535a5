"""Camera sets whose page went away for good: a job-queue worker ends each set idle for COACH_CAMERA_SET_IDLE_HOURS,
storing its session once when the buffered batches make one, else marking it failed; its batches are deleted either
way. Sets still sending, or idle for less, are left alone (backend.camera.sweep)."""

from __future__ import annotations

import datetime as dt
import uuid

from sqlalchemy import func, select, update

from backend.audit.models import AuditEvent
from backend.camera.models import CameraBatch, CameraSet
from backend.camera.sweep import queue_idle_sets
from backend.database import utcnow
from backend.jobs.models import Job
from backend.sessions.models import ExerciseSession
from backend.sessions.service import session_file as stored_file
from kinect_agent.formats import session_file
from tests.backend.camera.landmarks import batch, squats

PER_BATCH = 6  # frames per batch: 0.2 s at 30 fps


def _send(client, set_id, frames, headers, first_seq: int = 0) -> int:
    """Sends the frames in batches from batch number first_seq; returns the last batch number sent."""
    seq = first_seq - 1
    for seq, k in enumerate(range(0, len(frames), PER_BATCH), start=first_seq):
        r = client.post(f"/api/v1/camera/sets/{set_id}/batches", json=batch(seq, frames[k : k + PER_BATCH]),
                        headers=headers)  # fmt: skip
        assert r.status_code == 201, r.text
    return seq


def _age(db_session, set_id: str, hours: float) -> None:
    """Moves the set's start and its batches' arrival hours into the past (the page went quiet hours ago)."""
    sid, then = uuid.UUID(set_id), utcnow() - dt.timedelta(hours=hours)
    db_session.execute(update(CameraSet).where(CameraSet.id == sid).values(started_at=then - dt.timedelta(minutes=3)))
    db_session.execute(update(CameraBatch).where(CameraBatch.set_id == sid).values(received_at=then))
    db_session.flush()


def _row(db_session, set_id: str) -> CameraSet:
    row = db_session.get(CameraSet, uuid.UUID(set_id), populate_existing=True)
    assert row is not None
    return row


def _count(db_session, model, *where) -> int:
    return db_session.scalar(select(func.count()).select_from(model).where(*where))


def test_an_abandoned_set_whose_batches_make_a_session_is_stored_once(client, db_session, camera_home, started,
                                                                     run_jobs):  # fmt: skip
    set_id, h = started(seconds_ago=120), camera_home["headers"]
    last_seq = _send(client, set_id, squats(3), h)
    _age(db_session, set_id, 25)  # the default idle time is 24 h
    assert run_jobs() == 1  # the worker queued the set's end, then ran it
    row = _row(db_session, set_id)
    assert (row.status, row.end_reason, row.error) == ("stored", "abandoned", None)
    stored = db_session.get(ExerciseSession, row.session_id)
    assert stored is not None and stored.client_session_id == uuid.UUID(set_id)
    payload = session_file.decode(stored_file(db_session=db_session, session_id=stored.id))
    assert payload.raw.meta.device == "webcam" and payload.raw.n_frames == len(squats(3))
    assert _count(db_session, CameraBatch, CameraBatch.set_id == row.id) == 0
    ends = db_session.scalars(select(AuditEvent).where(AuditEvent.object_id == set_id,
                                                       AuditEvent.action == "camera.end")).all()  # fmt: skip
    assert [(a.actor_user_id, a.detail["reason"]) for a in ends] == [(None, "abandoned")]
    # the next sweep finds nothing; the page coming back and ending the set gets the same session
    assert run_jobs() == 0
    r = client.post(f"/api/v1/camera/sets/{set_id}/end", json={"last_seq": last_seq}, headers=h)
    assert r.status_code == 200 and r.json()["session_id"] == stored.id, r.text
    patient = camera_home["patient"].id
    assert _count(db_session, ExerciseSession, ExerciseSession.patient_id == patient) == 1


def test_an_abandoned_set_too_short_to_analyse_is_failed_and_its_batches_deleted(client, db_session, camera_home,
                                                                                started, run_jobs):  # fmt: skip
    set_id, h = started(seconds_ago=120), camera_home["headers"]
    _send(client, set_id, squats(1)[:5], h)  # 5 frames: fewer than a set needs (limits.MIN_END_FRAMES)
    _age(db_session, set_id, 30)
    assert run_jobs() == 1
    row = _row(db_session, set_id)
    assert (row.status, row.end_reason, row.session_id) == ("failed", "abandoned", None)
    assert row.error is not None and "only 5 frames" in row.error, row.error
    assert _count(db_session, CameraBatch, CameraBatch.set_id == row.id) == 0
    assert _count(db_session, ExerciseSession, ExerciseSession.patient_id == camera_home["patient"].id) == 0


def test_an_abandoned_set_the_server_refuses_is_failed_with_the_reason(client, db_session, camera_home, started,
                                                                      run_jobs, settings, monkeypatch):  # fmt: skip
    set_id, h = started(seconds_ago=120), camera_home["headers"]
    _send(client, set_id, squats(3), h)
    _age(db_session, set_id, 25)
    monkeypatch.setattr(settings, "SESSION_MAX_FRAMES", 50)  # the set's session file exceeds the upload limit
    assert run_jobs() == 1
    row = _row(db_session, set_id)
    assert (row.status, row.session_id) == ("failed", None), row.error
    assert row.error is not None and "could not be stored" in row.error and "50" in row.error, row.error
    assert _count(db_session, CameraBatch, CameraBatch.set_id == row.id) == 0
    assert _count(db_session, ExerciseSession, ExerciseSession.patient_id == camera_home["patient"].id) == 0


def test_sets_still_sending_or_idle_for_less_than_the_setting_are_kept(client, db_session, camera_home, started,
                                                                      run_jobs):  # fmt: skip
    h = camera_home["headers"]
    quiet = started(seconds_ago=120)
    _send(client, quiet, squats(1), h)
    _age(db_session, quiet, 23)  # quiet, but for less than 24 h
    busy = started(seconds_ago=120)
    _send(client, busy, squats(1), h)
    db_session.execute(update(CameraSet).where(CameraSet.id == uuid.UUID(busy))
                       .values(started_at=utcnow() - dt.timedelta(hours=30)))  # fmt: skip
    assert run_jobs() == 0  # started 30 h ago, but its last batch came just now
    for set_id in (quiet, busy):
        row = _row(db_session, set_id)
        assert row.status == "recording" and _count(db_session, CameraBatch, CameraBatch.set_id == row.id) > 0


def test_a_set_that_sends_again_after_its_end_was_queued_is_left_recording(client, db_session, camera_home, started,
                                                                          run_jobs):  # fmt: skip
    set_id, h = started(seconds_ago=120), camera_home["headers"]
    frames = squats(3)
    last_seq = _send(client, set_id, frames[:60], h)
    _age(db_session, set_id, 25)
    assert queue_idle_sets(db_session=db_session, idle_hours=24) == 1
    assert queue_idle_sets(db_session=db_session, idle_hours=24) == 0, "queued once"
    db_session.execute(update(CameraSet).where(CameraSet.id == uuid.UUID(set_id))
                       .values(started_at=utcnow() - dt.timedelta(seconds=120)))  # fmt: skip
    last_seq = _send(client, set_id, frames[60:], h, first_seq=last_seq + 1)  # the page is back
    assert run_jobs() == 1  # the queued job ran and found the set active again
    row = _row(db_session, set_id)
    assert row.status == "recording" and row.last_seq == last_seq
    job = db_session.scalar(select(Job).where(Job.kind == "camera_end"))
    assert job.status == "done" and job.result["ended"] is False and job.result["status"] == "recording"
    _age(db_session, set_id, 25)  # quiet again: a new job (the key names the last batch) ends it
    assert run_jobs() == 1
    row = _row(db_session, set_id)
    assert row.status == "stored" and row.session_id is not None
