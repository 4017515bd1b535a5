"""Camera sets' queries and changes: consent, start, batches (checked, idempotent, rate-limited) and reads.

The end of a set (the offline pipeline and the stored session) is in finish.py; the live count in live_count.py.
Services flush, never commit: the request's transaction keeps a batch and its set's counters together.
"""

from __future__ import annotations

import datetime as dt
import uuid
from typing import Any, Literal, cast

import numpy as np
from sqlalchemy import delete, func, select
from sqlalchemy.engine import CursorResult
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from backend.camera import limits
from backend.camera.batch import MIN_STEP_S, check_batch, content_hash, follows, pack, unpack
from backend.camera.errors import (
    BatchConflict,
    BatchOutOfOrder,
    CameraRateLimited,
    CameraSetEnded,
    CameraSetNotFound,
    ConsentMissing,
)
from backend.camera.models import CameraBatch, CameraConsent, CameraSet
from backend.camera.schemas import BatchIn, CameraSetOut, ConsentOut
from backend.database import utcnow
from backend.exceptions import InvalidInput
from backend.exercises.models import Exercise
from backend.plans.service import patient_plan_item
from kinect_agent.sources.webcam.landmarks import LandmarkBatch

MAX_STARTS_PER_HOUR = 60  # sets a patient may start in an hour (a page restarting in a loop is stopped here)


def aware(when: dt.datetime) -> dt.datetime:
    """Returns when as an aware UTC time (SQLite gives naive times back)."""
    return when if when.tzinfo is not None else when.replace(tzinfo=dt.UTC)


# ---------------------------------------------------------------------------------------------- consent


def consent_status(*, db_session: Session, patient_id: int) -> ConsentOut:
    """Returns whether the patient agreed to the current consent text."""
    row = db_session.get(CameraConsent, patient_id)
    given = row is not None and row.consent_version == limits.CONSENT_VERSION
    return ConsentOut(
        patient_id=patient_id,
        consent_version=limits.CONSENT_VERSION,
        given=given,
        given_at=row.given_at if given and row is not None else None,
    )


def give_consent(*, db_session: Session, patient_id: int, consent_version: str) -> ConsentOut:
    """Records the patient's consent to the consent text consent_version (it must be the current one)."""
    if consent_version != limits.CONSENT_VERSION:
        raise InvalidInput(
            f"body.consent_version: {consent_version!r} is not the current consent text "
            f"({limits.CONSENT_VERSION}); reload the page to read it"
        )
    row = db_session.get(CameraConsent, patient_id)
    if row is None:
        row = CameraConsent(patient_id=patient_id)
        db_session.add(row)
    row.consent_version, row.given_at = consent_version, utcnow()
    db_session.flush()
    return consent_status(db_session=db_session, patient_id=patient_id)


def withdraw_consent(*, db_session: Session, patient_id: int) -> ConsentOut:
    """Removes the patient's consent: no new camera set starts until they agree again (stored sessions stay)."""
    row = db_session.get(CameraConsent, patient_id)
    if row is not None:
        db_session.delete(row)
        db_session.flush()
    return consent_status(db_session=db_session, patient_id=patient_id)


# ---------------------------------------------------------------------------------------------- sets


def _failure(row: CameraSet) -> Literal["too_short", "not_storable"] | None:
    """Returns why a failed set stored nothing (None for a set that did not fail)."""
    if row.status != "failed":
        return None
    return "too_short" if row.n_frames < limits.MIN_END_FRAMES else "not_storable"


def set_out(db_session: Session, row: CameraSet) -> CameraSetOut:
    """Returns the API view of a set."""
    exercise = db_session.get(Exercise, row.exercise_id)
    assert exercise is not None
    return CameraSetOut(
        set_id=str(row.id),
        patient_id=row.patient_id,
        plan_item_id=row.plan_item_id,
        exercise_slug=exercise.slug,
        target_reps=row.target_reps,
        angles=list(exercise.defining_angles),
        model=row.model_name,
        status=row.status,
        n_frames=row.n_frames,
        last_seq=row.last_seq,
        session_id=row.session_id,
        error=row.error,
        failure=_failure(row),
    )


def start_set(*, db_session: Session, patient_id: int, plan_item_id: int, model: str) -> CameraSet:
    """Starts a camera set of a plan item of the patient; raises PlanNotFound, ConsentMissing or CameraRateLimited."""
    item, exercise = patient_plan_item(db_session=db_session, patient_id=patient_id, plan_item_id=plan_item_id)
    if not consent_status(db_session=db_session, patient_id=patient_id).given:
        raise ConsentMissing("the patient has not agreed to recording with their camera yet (POST /camera/consent)")
    hour_ago = utcnow() - dt.timedelta(hours=1)
    recent = db_session.scalar(
        select(func.count())
        .select_from(CameraSet)
        .where(CameraSet.patient_id == patient_id, CameraSet.started_at >= hour_ago)
    )
    if recent is not None and recent >= MAX_STARTS_PER_HOUR:
        raise CameraRateLimited(f"{recent} camera sets were started in the last hour; wait a few minutes", 300)
    row = CameraSet(
        id=uuid.uuid4(),
        patient_id=patient_id,
        plan_item_id=item.id,
        exercise_id=exercise.id,
        target_reps=item.repetitions,
        model_name=model,
        status="recording",
        started_at=utcnow(),
    )
    db_session.add(row)
    db_session.flush()
    return row


def get_set(*, db_session: Session, patient_id: int, set_id: uuid.UUID, for_update: bool = False) -> CameraSet:
    """Returns the patient's set; raises CameraSetNotFound for an unknown set or another patient's."""
    query = select(CameraSet).where(CameraSet.id == set_id)
    if for_update:
        query = query.with_for_update()
    row = db_session.scalar(query.execution_options(populate_existing=True))
    if row is None or row.patient_id != patient_id:
        raise CameraSetNotFound(f"set {set_id} does not exist")
    return row


def _stored_batch(db_session: Session, set_id: uuid.UUID, seq: int) -> CameraBatch | None:
    return db_session.scalar(select(CameraBatch).where(CameraBatch.set_id == set_id, CameraBatch.seq == seq))


def _check_rates(row: CameraSet, batch: LandmarkBatch, now: dt.datetime) -> None:
    """Raises InvalidInput for frame times ahead of the set's clock, CameraRateLimited for more frames or batches
    than MAX_FPS and MAX_BATCHES_PER_S allow since the start (with RATE_SLACK_S seconds of allowance)."""
    elapsed = max((now - aware(row.started_at)).total_seconds(), 0.0)
    ahead = np.flatnonzero(batch.t > elapsed + limits.MAX_CLOCK_AHEAD_S)
    if ahead.size:
        i = int(ahead[0])
        raise InvalidInput(
            f"body.frames[{i}].t: {batch.t[i]:.3f} s is ahead of the set's clock ({elapsed:.1f} s since it started)"
        )
    allowance = elapsed + limits.RATE_SLACK_S
    if row.n_frames + batch.n_frames > limits.MAX_FPS * allowance:
        raise CameraRateLimited(f"more than {limits.MAX_FPS:g} frames a second since the set started")
    if row.n_batches + 1 > limits.MAX_BATCHES_PER_S * allowance:
        raise CameraRateLimited(f"more than {limits.MAX_BATCHES_PER_S:g} batches a second since the set started")


def add_batch(*, db_session: Session, row: CameraSet, body: BatchIn) -> tuple[LandmarkBatch, bool]:
    """Stores one batch of the set row (locked by the caller); returns (its frames, repeated).

    A batch number received before with the same frames is a repeat (nothing stored, repeated=True); with other
    frames BatchConflict; after the end (its batches are gone then, drop_batches) any number received is a repeat.
    Raises CameraSetEnded for a new batch after the end, BatchOutOfOrder when batches before it are missing,
    InvalidInput naming the field of an implausible value or of a time that goes back, CameraRateLimited.
    """
    data = pack(check_batch(body))
    digest = content_hash(data)
    batch = unpack(data, len(body.frames), (body.image_size[0], body.image_size[1]))  # as stored: float32 values
    if body.seq <= row.last_seq:
        stored = _stored_batch(db_session, row.id, body.seq)
        if stored is None and row.status != "recording":
            return batch, True
        if stored is None or stored.content_hash != digest:
            raise BatchConflict(f"batch {body.seq} of set {row.id} was received before with other frames")
        return batch, True
    if row.status != "recording":
        raise CameraSetEnded(f"set {row.id} ended ({row.status}); it takes no more batches")
    if body.seq != row.last_seq + 1:
        raise BatchOutOfOrder(f"body.seq: batch {body.seq} came before batch {row.last_seq + 1}; send them in order")
    if row.last_t is not None and not follows(batch.t[:1], np.array([row.last_t]))[0]:
        raise InvalidInput(
            f"body.frames[0].t: {batch.t[0]} s does not come {MIN_STEP_S:g} s or more after the last frame received "
            f"({row.last_t} s, batch {row.last_seq})"
        )
    _check_rates(row, batch, utcnow())
    # the set's counters first: on SQLite (pysqlite begins a transaction before the first write only) a savepoint
    # opened outside a transaction is one, and its release commits (one more disk sync per batch, and the batch
    # committed apart from its counters); after the UPDATE the savepoint is inside the request's transaction
    before = (row.last_seq, row.last_t, row.n_frames, row.n_batches)
    row.last_seq, row.last_t = body.seq, float(batch.t[-1])
    row.n_frames += batch.n_frames
    row.n_batches += 1
    db_session.flush()
    try:
        with db_session.begin_nested():
            db_session.add(
                CameraBatch(
                    set_id=row.id,
                    seq=body.seq,
                    n_frames=batch.n_frames,
                    t_first=float(batch.t[0]),
                    t_last=float(batch.t[-1]),
                    image_width=batch.image_size[0],
                    image_height=batch.image_size[1],
                    content_hash=digest,
                    data=data,
                    received_at=utcnow(),
                )
            )
    except IntegrityError:  # the same batch number arrived at the same time through another request
        row.last_seq, row.last_t, row.n_frames, row.n_batches = before
        db_session.flush()
        stored = _stored_batch(db_session, row.id, body.seq)
        if stored is None or stored.content_hash != digest:
            raise BatchConflict(f"batch {body.seq} of set {row.id} was received before with other frames") from None
        return batch, True
    return batch, False


def drop_batches(*, db_session: Session, set_id: uuid.UUID) -> int:
    """Deletes the landmark batches of a set that ended (the stored session holds its skeleton; the 33 landmarks
    with the face's are not kept beyond the set); returns how many there were."""
    done = db_session.execute(delete(CameraBatch).where(CameraBatch.set_id == set_id))
    return cast("CursorResult[Any]", done).rowcount or 0  # a DELETE's result is a CursorResult


def set_batches(*, db_session: Session, set_id: uuid.UUID, upto_seq: int | None = None) -> list[LandmarkBatch]:
    """Returns the set's stored batches in order (those up to upto_seq when given)."""
    query = select(CameraBatch).where(CameraBatch.set_id == set_id).order_by(CameraBatch.seq)
    if upto_seq is not None:
        query = query.where(CameraBatch.seq <= upto_seq)
    return [unpack(b.data, b.n_frames, (b.image_width, b.image_height)) for b in db_session.scalars(query)]
