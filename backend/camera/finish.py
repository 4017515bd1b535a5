"""The end of a camera set: the set's landmarks -> the 20-joint recording -> the full offline pipeline with the
webcam's settings -> a session file (device `webcam`, the model's name and hash, the frame rate achieved) ->
stored through the same path as an uploaded session, once.

The session's client id is the set's id and the file's bytes depend only on the stored batches, so an end that is
repeated (a retry after a lost answer, two tabs) finds the stored session and stores nothing twice.
"""

from __future__ import annotations

import datetime as dt
from typing import Any

import numpy as np
from sqlalchemy.orm import Session

from backend.camera import limits, live_count, service
from backend.camera.errors import BatchOutOfOrder
from backend.camera.models import CameraSet
from backend.camera.skeleton import WEBCAM, pipeline_config, to_recording
from backend.camera.vendor import model_info
from backend.database import utcnow
from backend.events.hub import Event, publish
from backend.exceptions import InvalidSessionFile
from backend.exercises.models import Exercise
from backend.i18n import N_
from backend.session_review import service as review
from backend.sessions.ingest import decode_upload
from kinect_agent.formats import session_file
from kinect_agent.formats.session_file import SessionFileError, SessionPayload
from kinect_agent.processing.pipeline import process
from kinect_agent.processing.provenance import pipeline_params
from kinect_agent.recording import Metadata
from kinect_agent.sources.webcam.header import webcam_header
from kinect_agent.vendor import load_lock


def _iso(when: dt.datetime) -> str:
    when = when if when.tzinfo is not None else when.replace(tzinfo=dt.UTC)
    return when.astimezone(dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def browser_runtime() -> str:
    """Returns the page's pose runtime as the header names it ("@mediapipe/tasks-vision 1.1.0 (browser)")."""
    package = next(p for p in load_lock()["npm"] if p["name"] == "@mediapipe/tasks-vision")
    return f"{package['name']} {package['version']} (browser)"


def frame_rate(t: np.ndarray) -> float | None:
    """Returns the camera's frame rate (Hz) over frame times t (T,) s: one over the median step, so that the time the
    patient was out of the picture or the page hidden (frames missing, not slower) does not lower it; None when no
    two frames differ in time."""
    steps = np.diff(t)
    steps = steps[steps > 0]
    return round(float(1.0 / np.median(steps)), 2) if steps.size else None


def session_bytes(row: CameraSet, exercise: Exercise, db_session: Session) -> bytes | None:
    """Returns the session file of the set's stored batches (None when they hold fewer than MIN_END_FRAMES)."""
    batches = service.set_batches(db_session=db_session, set_id=row.id)
    n_frames = sum(b.n_frames for b in batches)
    if n_frames < limits.MIN_END_FRAMES:
        return None
    fps = frame_rate(np.concatenate([b.t for b in batches]))
    model = model_info(row.model_name)
    header = webcam_header(model=row.model_name.removeprefix("pose_landmarker_"), runtime=browser_runtime(),
                           fps_achieved=fps, image_size=batches[-1].image_size, images=n_frames)  # fmt: skip
    meta = Metadata(device=WEBCAM, rate_hz=fps, exercise=exercise.slug, source="browser camera",
                    extra={"webcam": header, "camera_set_id": str(row.id)})  # fmt: skip
    raw = session_file.as_stored(to_recording(batches, meta))  # filter what the file holds (a re-filter matches)
    config = pipeline_config()
    result = process(raw, config=config)
    params = {**pipeline_params(config, result), "device": WEBCAM, "model": model, "fps_achieved": fps}
    payload = SessionPayload(
        session_id=str(row.id),
        raw=raw,
        filtered=result.filtered,
        params=params,
        created_at=_iso(row.started_at),
        angle_sd=result.angle_sd,
    )
    return session_file.encode(payload)


def _ended_message(row: CameraSet, exercise: Exercise, count: int, hint: str | None = None) -> dict[str, Any]:
    state = "ended" if row.status == "stored" else "failed"
    return {
        "set_id": str(row.id),
        "exercise_slug": exercise.slug,
        "state": state,
        "count": count,
        "target": row.target_reps,
        "reason": row.end_reason,
        "session_id": str(row.id),
        "hint": hint,
        "elapsed_s": round(row.last_t or 0.0, 2),
        "device": WEBCAM,
    }


def _fail(db_session: Session, row: CameraSet, exercise: Exercise, count: int | None, error: str, said: str) -> None:
    """Marks the set failed with error (for its API view), says `said` (a catalogue message: the live view shows it in
    its reader's language) on the live channel, deletes its batches."""
    row.status, row.error = "failed", error
    publish(db_session, Event("live.progress", row.patient_id, _ended_message(row, exercise, count or 0, said)))
    service.drop_batches(db_session=db_session, set_id=row.id)
    db_session.flush()
    live_count.forget(row.id)


def end_set(
    *, db_session: Session, row: CameraSet, last_seq: int, reason: str, max_frames: int, max_decoded_bytes: int
) -> CameraSet:
    """Ends the set row (locked by the caller) and returns it: status stored with session_id, or failed with the
    reason in error (too few frames, or frames no session file may hold); either way its landmark batches are
    deleted. A set that ended already is returned as it is. Raises BatchOutOfOrder when
    the page sent batches the server has not received (last_seq > row.last_seq): it sends them, then ends again.
    max_frames, max_decoded_bytes: the limits of an uploaded session file (Settings.SESSION_MAX_*)."""
    if row.status != "recording":
        return row
    if last_seq > row.last_seq:
        raise BatchOutOfOrder(
            f"body.last_seq: batches {row.last_seq + 1}..{last_seq} were not received; send them, then end the set"
        )
    exercise = db_session.get(Exercise, row.exercise_id)
    assert exercise is not None
    row.ended_at, row.end_reason = utcnow(), reason
    count = live_count.final_count(row.id)
    try:
        data = session_bytes(row, exercise, db_session)
        upload = (
            None if data is None else decode_upload(data, max_frames=max_frames, max_decoded_bytes=max_decoded_bytes)
        )
    except (SessionFileError, InvalidSessionFile) as exc:  # the same frames fail the same way again: said, not retried
        error = f"the set's {row.n_frames} frames could not be stored as a session: {exc}"
        _fail(db_session, row, exercise, count, error, N_("The set could not be saved."))
        return row
    if upload is None:
        error = (
            f"only {row.n_frames} frames were received; at least {limits.MIN_END_FRAMES} are needed to analyse a set"
        )
        _fail(db_session, row, exercise, count, error, N_("The set was too short to save."))
        return row
    stored, created = review.store_upload(
        db_session=db_session, upload=upload, patient_id=row.patient_id, exercise=exercise, device_id=None
    )
    row.status, row.session_id = "stored", stored.id
    service.drop_batches(db_session=db_session, set_id=row.id)
    db_session.flush()
    if created:
        publish(
            db_session,
            Event("session.stored", row.patient_id, {"session_id": stored.id, "client_session_id": str(row.id)}),
        )
    publish(db_session, Event("live.progress", row.patient_id, _ended_message(row, exercise, count or 0)))
    live_count.forget(row.id)
    return row
