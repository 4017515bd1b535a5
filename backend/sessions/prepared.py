"""The session page's detail prepared off the request path: built once by a job-queue worker, kept in the object store.

The file-derived part of GET /sessions/{id}/detail (backend.sessions.detail: decoding, the outlier model, curves,
quality) costs seconds of CPU and up to GiBs on a long recording, so a request never computes it: it reads the
stored JSON document (content-addressed in the object store, one `session_detail` row per session) and adds the
session row's own fields, or queues the build (key `detail:<session id>:<inputs>`) and answers where it is. The
document is keyed by `inputs`, the sha256 of everything it is made from (the file's sha256, the exercise, the
stored metrics document, DETAIL_VERSION): a re-analysis or a new version makes it stale and the next ask queues a
new build. Uploads queue the build at once, so a session is usually ready before anyone opens it.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from backend.database import keep_row
from backend.exceptions import InvalidSessionFile, SessionNotFound
from backend.i18n import ENGLISH, Translator
from backend.jobs.asking import ask
from backend.jobs.models import Job
from backend.jobs.queue import enqueue
from backend.sessions import detail, service
from backend.sessions.models import SessionDetail
from backend.sessions.schemas import SessionDetailOut
from backend.storage import get_store
from backend.storage.base import StoredObject

KIND = "detail"
ROW_KEYS = ("session_id", "patient_id", "exercise_slug", "exercise_name", "started_at", "status", "error")
ROW_PROCESSING = ("version", "params")  # of "processing": the row's, not the file's


@dataclass(frozen=True)
class DetailState:
    """A detail not stored yet: "preparing" (queued or being built) or "failed" (for good); detail in words."""

    state: str
    detail: str


def inputs_of(*, content_hash: str, slug: str | None, document: dict[str, Any] | None) -> str:
    """Returns the sha256 (64 hex digits) naming what a session's detail is made from: its file's sha256, its
    exercise, its stored metrics document and DETAIL_VERSION."""
    what = {"file": content_hash, "exercise": slug, "document": document, "version": detail.DETAIL_VERSION}
    text = json.dumps(what, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def _inputs_of_row(row: tuple[Any, ...]) -> str:
    session, slug, _, _, _, document = row
    return inputs_of(content_hash=session.content_hash, slug=slug, document=document)


def job_key(session_id: int, inputs: str) -> str:
    """Returns the queue key of the build of one session's detail from `inputs` (inputs_of)."""
    return f"{KIND}:{session_id}:{inputs}"


def queue_build(*, db_session: Session, session_id: int) -> None:
    """Queues the build of a session's detail (at upload, after a re-analysis); flushes. Once per inputs."""
    row = service.get_session_row(db_session=db_session, session_id=session_id)
    key = job_key(session_id, _inputs_of_row(row))
    enqueue(db_session=db_session, kind=KIND, items=[(key, {"session_id": session_id})])


def _stored_document(db_session: Session, session_id: int, inputs: str) -> dict[str, Any] | None:
    row = db_session.execute(
        select(SessionDetail.data_key, SessionDetail.data_hash).where(
            SessionDetail.session_id == session_id, SessionDetail.inputs == inputs
        )
    ).first()
    if row is None:
        return None
    return json.loads(get_store().get(row.data_key, row.data_hash))


def with_row(document: dict[str, Any], row: tuple[Any, ...]) -> dict[str, Any]:
    """Returns the detail body (keys: SessionDetailOut): the stored document with the session row's own fields."""
    session, slug, _, _, _, _ = row
    spec_name = document.get("exercise_name")
    own = {"session_id": session.id, "patient_id": session.patient_id, "exercise_slug": slug,
           "exercise_name": spec_name, "started_at": session.started_at, "status": session.status,
           "error": session.error}  # fmt: skip
    processing = dict(document.get("processing") or {})
    processing |= {"version": session.processing_version or "", "params": session.processing_params or {}}
    return document | own | {"processing": processing}


def read_detail(*, db_session: Session, row: tuple[Any, ...], t: Translator = ENGLISH) -> dict[str, Any] | DetailState:
    """Returns the detail body of get_session_row's row when it is stored, else where its build is (queueing it
    when it is neither stored nor queued, or failed and may be tried again); flushes.

    Raises SessionFileRemoved when the retention period removed the recording, InvalidSessionFile when its stored
    file cannot be shown (the build found it so: no retry will change it). t: the reader's language (the body's
    texts and the state's words).
    """
    session = row[0]
    inputs = _inputs_of_row(row)
    document = _stored_document(db_session, session.id, inputs)
    if document is not None:
        return detail.in_language(with_row(document, row), t)
    service.require_recording(db_session=db_session, session_id=session.id)
    key = job_key(session.id, inputs)
    done = db_session.scalar(select(Job.result).where(Job.key == key, Job.status == "done"))
    if isinstance(done, dict) and done.get("invalid"):
        raise InvalidSessionFile(str(done["invalid"]))
    found = ask(db_session=db_session, kind=KIND, key=key, payload={"session_id": session.id}, t=t)
    return DetailState(found.state, found.detail)


def run(*, db_session: Session, session_id: int, max_frames: int, max_decoded_bytes: int) -> dict[str, Any]:
    """Runs the job of one session: builds and stores its detail document unless one of today's inputs is stored;
    a file that cannot be shown is a result (`invalid`, said to whoever asks), not a failure to retry."""
    try:
        row = service.get_session_row(db_session=db_session, session_id=session_id)
    except SessionNotFound:
        return {"session_id": session_id, "built": False, "skipped": "the session no longer exists"}
    inputs = _inputs_of_row(row)
    if _stored_document(db_session, session_id, inputs) is not None:
        return {"session_id": session_id, "built": False, "inputs": inputs}
    data = service.session_file(db_session=db_session, session_id=session_id)
    session, slug, _, _, _, stored = row
    try:
        body = detail.detail_body(session, slug, stored, data, max_frames=max_frames,
                                  max_decoded_bytes=max_decoded_bytes)  # fmt: skip
    except InvalidSessionFile as exc:
        return {"session_id": session_id, "built": False, "inputs": inputs, "invalid": exc.message}
    body = SessionDetailOut.model_validate(body).model_dump(mode="json")  # as the API says it: NaN as null
    document = {k: v for k, v in body.items() if k not in ROW_KEYS or k == "exercise_name"}
    document["processing"] = {k: v for k, v in body["processing"].items() if k not in ROW_PROCESSING}
    text = json.dumps(document, separators=(",", ":"), allow_nan=False).encode()
    obj = get_store().put(KIND, text)
    _keep(db_session, session_id, inputs, obj)
    return {"session_id": session_id, "built": True, "inputs": inputs, "size": obj.size}


def _keep(db_session: Session, session_id: int, inputs: str, obj: StoredObject) -> None:
    """Points the session's row at the stored document (replacing a stale one); a concurrent insert wins."""
    fields = {"inputs": inputs, "data_key": obj.key, "data_hash": obj.sha256, "size": obj.size}
    keep_row(db_session, SessionDetail, {"session_id": session_id}, fields)
