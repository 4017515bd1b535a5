"""The upload queue on disk: every session is saved here (durably) before any upload is tried.

    queue/captured/<session id>.khs     a raw session held while it is being filtered (recover_held queues it)
    queue/pending/<session id>.khs      waiting for the server (written atomically, file and folder fsynced)
    queue/sent/<session id>.json        the server's receipt (written before the pending file is removed)
    queue/sent/<session id>.khs         the uploaded file itself, only with keep_sent=True
    queue/rejected/<session id>.khs     refused by the server (a 4xx) ...
    queue/rejected/<session id>.error.json   ... with the server's error
    queue/pending/<session id>.failures.json the server errors (5xx) a pending file met, pass after pass ...
    queue/held/<session id>.khs         ... and, after HOLD_AFTER_SERVER_ERRORS of them, the file set aside so that
    queue/held/<session id>.error.json  the others go on (`kinect-agent upload --retry-held` queues it again)

A crash at any point leaves each session in exactly one of: pending (will be uploaded; the server deduplicates a
re-upload by session id + content hash), or sent/rejected/held. Temporary files (".*.part") never count as queued;
leftovers from a crash are removed by `clean_partial`. A process filtering a held raw session keeps an exclusive
lock on its captured file (where the system has flock), so `recover_held` takes the files of a dead process at once
and leaves a living one's alone.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import time
from dataclasses import dataclass
from io import BufferedReader
from pathlib import Path
from typing import Any

from kinect_agent.clock import utc_now_iso
from kinect_agent.config import fsync_dir
from kinect_agent.errors import AgentError
from kinect_agent.formats._atomic import atomic_open
from kinect_agent.formats.session_file import SessionPayload, encode

try:
    import fcntl
except ImportError:  # Windows: no flock; held files are recovered by age only
    fcntl = None  # type: ignore[assignment]

SUFFIX = ".khs"
HOLD_AFTER_SERVER_ERRORS = 5  # passes ending in the same kind of server error before a file is set aside
_SAFE_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]{0,127}$")
PARTIAL_GLOB = ".*.part"


class QueueError(AgentError):
    """The queue cannot take or move a session; names the session and the folder."""


@dataclass(frozen=True)
class QueueCounts:
    """How many sessions are in each part of the queue."""

    pending: int
    sent: int
    rejected: int
    held: int = 0


def check_session_id(session_id: str) -> str:
    """Returns the id if it is safe as a file name (letters, digits, - and _; at most 128); else raises QueueError."""
    if not isinstance(session_id, str) or not _SAFE_ID.match(session_id):
        raise QueueError(f"session id {session_id!r} cannot name a queue file (letters, digits, '-', '_' only)")
    return session_id


def _write_durably(path: Path, data: bytes) -> None:
    """Writes bytes atomically (temp file beside it, fsync, rename) and fsyncs the folder."""
    with atomic_open(path, "wb") as f:
        f.write(data)
    fsync_dir(path.parent)


def _write_json(path: Path, doc: dict[str, Any]) -> None:
    _write_durably(path, (json.dumps(doc, indent=2, sort_keys=True, default=str) + "\n").encode("utf-8"))


class SessionQueue:
    """The folder-based queue of one agent; safe to reopen after a crash."""

    def __init__(self, root: str | Path, *, keep_sent: bool = False) -> None:
        self.root = Path(root)
        self.keep_sent = keep_sent
        self.pending_dir = self.root / "pending"
        self.sent_dir = self.root / "sent"
        self.rejected_dir = self.root / "rejected"
        self.captured_dir = self.root / "captured"
        self.held_dir = self.root / "held"
        for folder in (self.captured_dir, self.pending_dir, self.sent_dir, self.rejected_dir, self.held_dir):
            folder.mkdir(parents=True, exist_ok=True)
        self._locks: dict[str, BufferedReader] = {}

    # ------------------------------------------------------------------------------------------ adding

    def enqueue(self, payload: SessionPayload) -> Path:
        """Encodes the session and saves it durably as pending/<session id>.khs; returns that path."""
        return self.enqueue_bytes(payload.session_id, encode(payload))

    def enqueue_bytes(self, session_id: str, data: bytes) -> Path:
        """Saves session file bytes as pending/<session id>.khs (atomic; fsync of file and folder).

        Enqueuing the same bytes again is a no-op; different bytes under a queued id raise QueueError, because the
        server would refuse them as a conflict and the first version must not be overwritten.
        """
        path = self.pending_dir / f"{check_session_id(session_id)}{SUFFIX}"
        if path.exists():
            if path.read_bytes() == data:
                return path
            raise QueueError(f"{path}: session {session_id} is already queued with different content")
        _write_durably(path, data)
        return path

    def hold(self, payload: SessionPayload) -> Path:
        """Saves a raw session durably in captured/ while it is processed, locked by this process; returns the path."""
        path = self.captured_dir / f"{check_session_id(payload.session_id)}{SUFFIX}"
        _write_durably(path, encode(payload))
        if fcntl is not None:
            lock = open(path, "rb")  # noqa: SIM115 - kept open until release: the lock lives with it
            fcntl.flock(lock.fileno(), fcntl.LOCK_EX)
            self._locks[payload.session_id] = lock
        return path

    def release(self, session_id: str) -> None:
        """Drops the held copy once the session is in pending/."""
        (self.captured_dir / f"{check_session_id(session_id)}{SUFFIX}").unlink(missing_ok=True)
        fsync_dir(self.captured_dir)
        lock = self._locks.pop(session_id, None)
        if lock is not None:
            lock.close()

    def recover_held(self, older_than_s: float = 1800.0) -> list[Path]:
        """Queues held sessions whose processing was interrupted (a crash); returns their pending paths.

        A held file that no living process has locked is taken at once; where the system has no flock, only files
        older than `older_than_s` are (a session another process is filtering right now stays with it: queuing its
        raw copy too would make the server refuse the filtered one as a conflict). A held copy of a session that
        is already pending, or that the server already confirmed (a crash between queuing and dropping the copy),
        is dropped instead: uploading it would be refused as other content under the same session id.
        """
        recovered = []
        limit = time.time() - older_than_s
        for path in sorted(self.captured_dir.glob(f"*{SUFFIX}")):
            if path.name.startswith(".") or not self._abandoned(path, limit):
                continue
            target = self.pending_dir / path.name
            if target.exists() or (self.sent_dir / f"{path.stem}.json").exists():
                path.unlink()
            else:
                os.replace(path, target)
                fsync_dir(self.pending_dir)
                recovered.append(target)
        fsync_dir(self.captured_dir)
        return recovered

    def _abandoned(self, path: Path, limit: float) -> bool:
        """True when no process works on the held file: unlocked (flock), else older than limit (epoch s)."""
        if path.stem in self._locks:
            return False
        if fcntl is None:
            return path.stat().st_mtime <= limit
        with open(path, "rb") as probe:
            try:
                fcntl.flock(probe.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                return False
            fcntl.flock(probe.fileno(), fcntl.LOCK_UN)
        return True

    # ------------------------------------------------------------------------------------------ reading

    def pending(self) -> list[Path]:
        """Returns the queued session files, oldest first (temporary files are never listed)."""
        files = [p for p in self.pending_dir.glob(f"*{SUFFIX}") if not p.name.startswith(".")]

        def key(p: Path) -> tuple[int, str]:
            try:
                return p.stat().st_mtime_ns, p.name
            except FileNotFoundError:  # sent by another uploader meanwhile
                return 0, p.name

        return sorted(files, key=key)

    def counts(self) -> QueueCounts:
        """Returns the number of pending, sent and rejected sessions."""
        return QueueCounts(
            pending=len(self.pending()),
            sent=len(list(self.sent_dir.glob("*.json"))),
            rejected=len(list(self.rejected_dir.glob(f"*{SUFFIX}"))),
            held=len(list(self.held_dir.glob(f"*{SUFFIX}"))),
        )

    def where(self, session_id: str) -> str | None:
        """Returns "captured", "pending", "sent" or "rejected" for a known session id, else None."""
        check_session_id(session_id)
        places = (
            ("pending", self.pending_dir / f"{session_id}{SUFFIX}"),
            ("sent", self.sent_dir / f"{session_id}.json"),
            ("rejected", self.rejected_dir / f"{session_id}{SUFFIX}"),
            ("held", self.held_dir / f"{session_id}{SUFFIX}"),
            ("captured", self.captured_dir / f"{session_id}{SUFFIX}"),
        )
        return next((name for name, path in places if path.exists()), None)

    def receipt(self, session_id: str) -> dict[str, Any] | None:
        """Returns the sent record of a session, or None when it has not been confirmed."""
        path = self.sent_dir / f"{check_session_id(session_id)}.json"
        try:
            return json.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            return None

    def rejection(self, session_id: str) -> dict[str, Any] | None:
        """Returns the server's error for a rejected or held session, or None."""
        for folder in (self.rejected_dir, self.held_dir):
            path = folder / f"{check_session_id(session_id)}.error.json"
            with contextlib.suppress(FileNotFoundError):
                return json.loads(path.read_text(encoding="utf-8"))
        return None

    def set_aside(self) -> list[dict[str, Any]]:
        """Returns the rejected and held sessions, each {"session_id", "where", "status_code", "detail", "at"}."""
        out = []
        for where, folder in (("rejected", self.rejected_dir), ("held", self.held_dir)):
            for path in sorted(folder.glob(f"*{SUFFIX}")):
                error = self.rejection(path.stem) or {}
                out.append({"session_id": path.stem, "where": where, "status_code": error.get("status_code"),
                            "detail": error.get("detail", ""),
                            "at": error.get("rejected_at") or error.get("held_at")})  # fmt: skip
        return out

    # ------------------------------------------------------------------------------------------ moving

    def mark_sent(self, path: Path, receipt: dict[str, Any]) -> Path:
        """Records the server's confirmation, then removes (or keeps in sent/) the pending file; returns the record.

        Only call this after the server answered 200/201: the record is written durably before the file goes.
        """
        session_id = self._id_of(path)
        record = {"session_id": session_id, "confirmed_at": utc_now_iso(), **receipt}
        out = self.sent_dir / f"{session_id}.json"
        _write_json(out, record)
        if self.keep_sent:
            with contextlib.suppress(FileNotFoundError):
                os.replace(path, self.sent_dir / path.name)
        else:
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
        (self.pending_dir / f"{session_id}.failures.json").unlink(missing_ok=True)
        fsync_dir(path.parent)
        return out

    def mark_rejected(self, path: Path, error: dict[str, Any]) -> Path:
        """Moves a pending file to rejected/ after writing the server's error beside it; returns the new path."""
        return self._set_aside(path, self.rejected_dir, {"rejected_at": utc_now_iso(), **error})

    def note_server_error(self, path: Path, status_code: int, detail: str) -> int:
        """Counts one more pass in which the server answered this pending file with status_code (a 5xx); returns
        how many passes in a row ended with that status (another status starts the count again)."""
        session_id = self._id_of(path)
        record_path = self.pending_dir / f"{session_id}.failures.json"
        with contextlib.suppress(FileNotFoundError, ValueError):
            record = json.loads(record_path.read_text(encoding="utf-8"))
            if record.get("status_code") == status_code:
                record.update(count=int(record.get("count", 0)) + 1, detail=detail, last_at=utc_now_iso())
                _write_json(record_path, record)
                return record["count"]
        _write_json(record_path, {"status_code": status_code, "count": 1, "detail": detail, "first_at": utc_now_iso(),
                                  "last_at": utc_now_iso()})  # fmt: skip
        return 1

    def mark_held(self, path: Path, error: dict[str, Any]) -> Path:
        """Sets a pending file aside in held/ with the server's repeated error; returns the new path."""
        return self._set_aside(path, self.held_dir, {"held_at": utc_now_iso(), **error})

    def _set_aside(self, path: Path, folder: Path, record: dict[str, Any]) -> Path:
        """Writes record as <id>.error.json in folder, then moves the pending file there; returns its new path."""
        session_id = self._id_of(path)
        _write_json(folder / f"{session_id}.error.json", {"session_id": session_id, **record})
        target = folder / path.name
        os.replace(path, target)
        (self.pending_dir / f"{session_id}.failures.json").unlink(missing_ok=True)
        fsync_dir(folder)
        fsync_dir(self.pending_dir)
        return target

    def requeue_rejected(self) -> list[Path]:
        """Moves every rejected file back to pending/ (after the cause was fixed); returns the new paths."""
        return self._requeue(self.rejected_dir)

    def requeue_held(self) -> list[Path]:
        """Moves every held file back to pending/ (the server was mended); returns the new paths."""
        return self._requeue(self.held_dir)

    def _requeue(self, folder: Path) -> list[Path]:
        moved = []
        for path in sorted(folder.glob(f"*{SUFFIX}")):
            target = self.pending_dir / path.name
            os.replace(path, target)
            (folder / f"{path.stem}.error.json").unlink(missing_ok=True)
            moved.append(target)
        fsync_dir(self.pending_dir)
        fsync_dir(folder)
        return moved

    def clean_partial(self, older_than_s: float = 600.0) -> list[Path]:
        """Removes temporary files left by a crash (older than `older_than_s`, so a running write is spared)."""
        removed = []
        limit = time.time() - older_than_s
        for folder in (self.captured_dir, self.pending_dir, self.sent_dir, self.rejected_dir, self.held_dir):
            for tmp in folder.glob(PARTIAL_GLOB):
                with contextlib.suppress(FileNotFoundError):
                    if tmp.stat().st_mtime <= limit:
                        tmp.unlink()
                        removed.append(tmp)
        return removed

    def _id_of(self, path: Path) -> str:
        path = Path(path)
        if path.parent.resolve() != self.pending_dir.resolve() or path.suffix != SUFFIX:
            raise QueueError(f"{path}: not a file of the queue's pending folder {self.pending_dir}")
        return check_session_id(path.stem)
