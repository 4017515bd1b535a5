"""Moves session files and replays between database blobs and the object store, in batches, resumably.

move_out: rows whose bytes are still in the database get them written to the store (content-addressed, so a
write repeated after a crash is harmless) and the key recorded, the blob cleared. move_in does the reverse (for a
downgrade below migration 0011). Both walk rows by id and pick up only rows not yet moved: run again after a
crash, they continue where they stopped. With commit=True (the CLI) each batch is committed on its own; in the
Alembic migration everything is one transaction, a crash rolls it back and the re-run skips the objects already
written (a HEAD or a stat instead of a write).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import sqlalchemy as sa
from sqlalchemy.engine import Connection

from backend.storage.base import ObjectStore, sha256_hex
from backend.storage.errors import StoredObjectMissing

_SESSION = sa.table(
    "exercise_session", sa.column("id"), sa.column("file_bytes"), sa.column("file_key"), sa.column("content_hash")
)
_REPLAY = sa.table("session_replay", sa.column("id"), sa.column("data"), sa.column("data_key"), sa.column("data_hash"))

Progress = Callable[[str], None]


@dataclass
class MoveReport:
    """What one run moved: session files and replays, and session rows left where they were (bytes that do not
    match their recorded sha256: the check names them)."""

    sessions: int = 0
    replays: int = 0
    replays_dropped: int = 0  # move_in only: replays whose object was gone (rebuilt from the file on next view)
    skipped: list[int] = field(default_factory=list)

    def text(self) -> str:
        """Returns the report in words."""
        out = f"{self.sessions} session file(s) and {self.replays} replay(s) moved"
        if self.replays_dropped:
            out += f", {self.replays_dropped} replay(s) without their object dropped (rebuilt on the next view)"
        if self.skipped:
            out += f"; sessions left in the database (bytes do not match their sha256): {self.skipped}"
        return out


def _batches(
    conn: Connection, query_for: Callable[[int], sa.Select[Any]], batch: int
) -> Iterator[Sequence[sa.Row[Any]]]:
    last = 0
    while True:
        rows = conn.execute(query_for(last).order_by(sa.text("id")).limit(batch)).all()
        if not rows:
            return
        yield rows
        last = rows[-1].id


def move_out(
    conn: Connection, store: ObjectStore, *, batch: int = 100, commit: bool = False, progress: Progress | None = None
) -> MoveReport:
    """Moves every database blob to the store; returns what it did (see module doc)."""
    report = MoveReport()
    pending = sa.and_(_SESSION.c.file_bytes.is_not(None), _SESSION.c.file_key.is_(None))
    left = conn.scalar(sa.select(sa.func.count()).select_from(_SESSION).where(pending))
    q = lambda last: sa.select(_SESSION.c.id, _SESSION.c.file_bytes, _SESSION.c.content_hash).where(  # noqa: E731
        _SESSION.c.file_key.is_(None), _SESSION.c.file_bytes.is_not(None), _SESSION.c.id > last
    )
    for rows in _batches(conn, q, batch):
        for row in rows:
            if sha256_hex(row.file_bytes) != row.content_hash:
                report.skipped.append(row.id)
                continue
            obj = store.put("session", row.file_bytes)
            conn.execute(sa.update(_SESSION).where(_SESSION.c.id == row.id).values(file_key=obj.key, file_bytes=None))
            report.sessions += 1
        if commit:
            conn.commit()
        if progress:
            progress(f"session files: {report.sessions + len(report.skipped)} of {left}")
    q = lambda last: sa.select(_REPLAY.c.id, _REPLAY.c.data).where(  # noqa: E731
        _REPLAY.c.data_key.is_(None), _REPLAY.c.data.is_not(None), _REPLAY.c.id > last
    )
    for rows in _batches(conn, q, batch):
        for row in rows:
            obj = store.put("replay", row.data)
            conn.execute(
                sa.update(_REPLAY)
                .where(_REPLAY.c.id == row.id)
                .values(data_key=obj.key, data_hash=obj.sha256, data=None)  # fmt: skip
            )
            report.replays += 1
        if commit:
            conn.commit()
        if progress:
            progress(f"replays: {report.replays}")
    return report


def move_in(
    conn: Connection, store: ObjectStore, *, batch: int = 100, commit: bool = False, progress: Progress | None = None
) -> MoveReport:
    """Moves every stored object back into its row (the objects stay in the store); a session whose object is
    missing or corrupt stops the run with StoredObjectMissing/StoredObjectCorrupt, nothing of it lost."""
    report = MoveReport()
    q = lambda last: sa.select(_SESSION.c.id, _SESSION.c.file_key, _SESSION.c.content_hash).where(  # noqa: E731
        _SESSION.c.file_key.is_not(None), _SESSION.c.id > last
    )
    for rows in _batches(conn, q, batch):
        for row in rows:
            data = store.get(row.file_key, row.content_hash)
            conn.execute(sa.update(_SESSION).where(_SESSION.c.id == row.id).values(file_bytes=data, file_key=None))
            report.sessions += 1
        if commit:
            conn.commit()
        if progress:
            progress(f"session files back in the database: {report.sessions}")
    q = lambda last: sa.select(_REPLAY.c.id, _REPLAY.c.data_key, _REPLAY.c.data_hash).where(  # noqa: E731
        _REPLAY.c.data_key.is_not(None), _REPLAY.c.id > last
    )
    for rows in _batches(conn, q, batch):
        for row in rows:
            try:
                data = store.get(row.data_key, row.data_hash)
            except StoredObjectMissing:
                conn.execute(sa.delete(_REPLAY).where(_REPLAY.c.id == row.id))
                report.replays_dropped += 1
                continue
            conn.execute(
                sa.update(_REPLAY).where(_REPLAY.c.id == row.id).values(data=data, data_key=None, data_hash=None)
            )
            report.replays += 1
        if commit:
            conn.commit()
        if progress:
            progress(f"replays back in the database: {report.replays}")
    return report
