"""A session's downloads (csv, trc, bvh, fhir) prepared off the request path when the recording is long.

Building an export decodes the whole file, analyses it again when no metrics are stored, and writes every frame:
for the longest accepted recording (2 h, 216 000 frames) 2-28 s of CPU and up to 1.1 GiB (bench/README.md). So a
request builds it only for a recording within both of EXPORT_DIRECT_MAX_S seconds and EXPORT_DIRECT_MAX_FRAMES
frames (`in_request`: the bound the budget was measured at, ≤ 2 s CPU and ≤ 256 MiB); a longer one is built once
by a job-queue worker (key `export:<session id>:<format>:<inputs>`), kept in the object store (one
`session_export` row per session and format) and read from there, the request answering 202 with where the
build is until then, as the session page's detail does (backend.sessions.prepared). `inputs` is the sha256 of
everything the file is made from (the session file's sha256, the exercise, the stored metrics document, who and
when it describes, how the set felt, EXPORT_VERSION): a re-analysis or a new answer makes the stored file stale and
the next ask queues a new build.
"""

from __future__ import annotations

import dataclasses
import gzip
import hashlib
import json
from dataclasses import dataclass
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from backend.database import keep_row
from backend.exceptions import ExportUnavailable, InvalidSessionFile, SessionNotFound
from backend.i18n import ENGLISH, Translator
from backend.jobs.asking import ask
from backend.jobs.models import Job
from backend.sessions import service
from backend.sessions.export import export_context, session_export
from backend.sessions.models import SessionExport
from backend.storage import get_store
from backend.storage.base import StoredObject
from kinect_agent.export.fhir import SessionContext
from kinect_agent.export.files import ExportFile

KIND = "export"
GZIP_LEVEL = 6  # the stored file's compression: built once, handed out as it is to clients that accept gzip
# part of a stored export's inputs: bump when kinect_agent.export's output changes (2: FHIR notes from basis ids)
EXPORT_VERSION = 2
NAMES = {"csv": "tables (CSV)", "trc": "OpenSim markers (TRC)", "bvh": "motion (BVH)", "fhir": "health record (FHIR)"}


@dataclass(frozen=True)
class StoredExport:
    """A download read from the object store: its bytes gzip-compressed as stored (a request hands them on as they
    are to a client that accepts gzip, so no request compresses the file again), media type and file name."""

    gzipped: bytes
    media_type: str
    file_name: str

    def data(self) -> bytes:
        """Returns the download's bytes, uncompressed."""
        return gzip.decompress(self.gzipped)


@dataclass(frozen=True)
class ExportState:
    """A download not stored yet: "preparing" (queued or being built) or "failed" (for good); detail in words."""

    state: str
    detail: str


def in_request(*, duration_s: float, n_frames: int, max_s: float, max_frames: int) -> bool:
    """Returns whether a recording of duration_s seconds and n_frames frames is exported within the request: both
    within their limit (the frames bound the writing, the duration the analysis a missing metrics document needs)."""
    return n_frames <= max_frames and duration_s <= max_s


def inputs_of(
    *, content_hash: str, slug: str | None, document: dict[str, Any] | None, fmt: str, context: SessionContext
) -> str:
    """Returns the sha256 (64 hex digits) naming what a session's `fmt` export is made from: its file's sha256, its
    exercise, its stored metrics document, its context (ids, start, feeling) and EXPORT_VERSION."""
    what = {"file": content_hash, "exercise": slug, "document": document, "format": fmt,
            "context": dataclasses.asdict(context), "version": EXPORT_VERSION}  # fmt: skip
    text = json.dumps(what, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def _inputs_of_row(row: tuple[Any, ...], fmt: str, context: SessionContext) -> str:
    session, slug, _, _, _, document = row
    return inputs_of(content_hash=session.content_hash, slug=slug, document=document, fmt=fmt, context=context)


def job_key(session_id: int, fmt: str, inputs: str) -> str:
    """Returns the queue key of the build of one session's `fmt` export from `inputs` (inputs_of)."""
    return f"{KIND}:{session_id}:{fmt}:{inputs}"


def _stored(db_session: Session, session_id: int, fmt: str, inputs: str) -> StoredExport | None:
    row = db_session.execute(
        select(SessionExport.data_key, SessionExport.data_hash, SessionExport.media_type, SessionExport.file_name)
        .where(SessionExport.session_id == session_id, SessionExport.format == fmt, SessionExport.inputs == inputs)
    ).first()  # fmt: skip
    if row is None:
        return None
    return StoredExport(get_store().get(row.data_key, row.data_hash), row.media_type, row.file_name)


def stored_for_today(
    *, db_session: Session, row: tuple[Any, ...], fmt: str, context: SessionContext
) -> StoredExport | None:
    """Returns the `fmt` export of get_session_row's row stored for today's inputs (read from the object store, its
    sha256 checked: raises StorageError when missing or corrupt), else None; queues nothing."""
    return _stored(db_session, row[0].id, fmt, _inputs_of_row(row, fmt, context))


def read_export(
    *, db_session: Session, row: tuple[Any, ...], fmt: str, t: Translator = ENGLISH
) -> StoredExport | ExportState:
    """Returns the stored `fmt` export of get_session_row's row when it is stored for today's inputs, else where
    its build is (queueing it when it is neither stored nor queued, or failed and may be tried again); flushes.

    Raises SessionFileRemoved when the retention period removed the recording, InvalidSessionFile when its stored
    file cannot be read and ExportUnavailable when the format needs metrics none can give (the build found it so:
    no retry will change it). t: the language the state is said in.
    """
    session = row[0]
    inputs = _inputs_of_row(row, fmt, export_context(db_session=db_session, row=row))
    stored = _stored(db_session, session.id, fmt, inputs)
    if stored is not None:
        return stored
    service.require_recording(db_session=db_session, session_id=session.id)
    key = job_key(session.id, fmt, inputs)
    done = db_session.scalar(select(Job.result).where(Job.key == key, Job.status == "done"))
    if isinstance(done, dict) and done.get("invalid"):
        raise InvalidSessionFile(str(done["invalid"]))
    if isinstance(done, dict) and done.get("unavailable"):
        raise ExportUnavailable(str(done["unavailable"]))
    found = ask(db_session=db_session, kind=KIND, key=key, payload={"session_id": session.id, "format": fmt},
                params={"file": NAMES.get(fmt, fmt)}, t=t)  # fmt: skip
    return ExportState(found.state, found.detail)


def run(*, db_session: Session, session_id: int, fmt: str, max_frames: int, max_decoded_bytes: int) -> dict[str, Any]:
    """Runs the job of one session's `fmt` export: builds it whole, then stores it gzip-compressed, unless one of
    today's inputs is stored; a file that cannot be read or exported is a result (said to whoever asks), not a
    failure to retry. Nothing is stored when the build fails: the object is written (atomically) only once its
    bytes are complete, its row after it."""
    try:
        row = service.get_session_row(db_session=db_session, session_id=session_id)
    except SessionNotFound:
        return {"session_id": session_id, "format": fmt, "built": False, "skipped": "the session no longer exists"}
    context = export_context(db_session=db_session, row=row)
    inputs = _inputs_of_row(row, fmt, context)
    done = {"session_id": session_id, "format": fmt, "built": False, "inputs": inputs}
    if db_session.scalar(
        select(SessionExport.id).where(
            SessionExport.session_id == session_id, SessionExport.format == fmt, SessionExport.inputs == inputs
        )
    ):
        return done
    try:
        file = session_export(db_session=db_session, row=row, fmt=fmt, max_frames=max_frames,
                              max_decoded_bytes=max_decoded_bytes, context=context)  # fmt: skip
    except InvalidSessionFile as exc:
        return done | {"invalid": exc.message}
    except ExportUnavailable as exc:
        return done | {"unavailable": exc.message}
    obj = get_store().put(KIND, gzip.compress(file.data, compresslevel=GZIP_LEVEL, mtime=0))
    _keep(db_session, session_id, fmt, inputs, obj, file)
    return done | {"built": True, "size": obj.size}


def _keep(db_session: Session, session_id: int, fmt: str, inputs: str, obj: StoredObject, file: ExportFile) -> None:
    """Points the session's row of `fmt` at the stored file (replacing a stale one); a concurrent insert wins."""
    fields = {"inputs": inputs, "data_key": obj.key, "data_hash": obj.sha256, "size": obj.size,
              "media_type": file.media_type, "file_name": file.file_name}  # fmt: skip
    keep_row(db_session, SessionExport, {"session_id": session_id, "format": fmt}, fields)
