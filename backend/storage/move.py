"""Moves session files and replays between database blobs and the object store, in batches, resumably.

move_out: rows whose bytes are still in the database get them written to the store (content-addressed, so a
write repeated after a crash is harmless) and the key recorded, the blob cleared. move_in does the reverse (for a
downgrade below migration 0011). Both walk rows by id and pick up only rows not yet moved: run again after a
crash, they continue where they stopped. With commit=True (the CLI) each batch is committed on its own; in the
Alembic migration everything is one transaction, a crash rolls it back and the re-run skips the objects already
written (a HEAD or a stat instead of a write).

move_in with commit=True deletes each object once the batch holding its bytes in the database is committed, and
only when no row points to it any more (two sessions with the same bytes share an object, and an earlier file of
a re-analysed session is named by session_metric_version). A crash between the commit and the deletes leaves
those objects behind: the next run finds them (a key no row points to whose sha256 is that of bytes a row holds)
and deletes them, so a completed move-in leaves nothing for `storage check` to count as unreferenced. Inside the
migration (commit=False) nothing is deleted, since a rollback would leave rows pointing to deleted objects; the
report says how many stay. Run move-in with the server stopped: an upload of the same bytes between its put and
its row could otherwise lose its object.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import sqlalchemy as sa
from sqlalchemy.engine import Connection

from backend.storage.base import ObjectStore, is_object_key, sha256_hex
from backend.storage.errors import StoredObjectMissing

_SESSION = sa.table(
    "exercise_session", sa.column("id"), sa.column("file_bytes"), sa.column("file_key"), sa.column("content_hash")
)
_REPLAY = sa.table("session_replay", sa.column("id"), sa.column("data"), sa.column("data_key"), sa.column("data_hash"))
_EARLIER = sa.table("session_metric_version", sa.column("file_key"))

Progress = Callable[[str], None]


@dataclass
class MoveReport:
    """What one run moved: session files and replays, and session rows left where they were (bytes that do not
    match their recorded sha256: the check names them)."""

    sessions: int = 0
    replays: int = 0
    replays_dropped: int = 0  # move_in only: replays whose object was gone (rebuilt from the file on next view)
    deleted: int = 0  # move_in only: objects deleted from the store, their bytes committed back in the database
    kept: int = 0  # move_in only (in the migration's transaction): objects left in the store
    skipped: list[int] = field(default_factory=list)

    def text(self) -> str:
        """Returns the report in words."""
        out = f"{self.sessions} session file(s) and {self.replays} replay(s) moved"
        if self.replays_dropped:
            out += f", {self.replays_dropped} replay(s) without their object dropped (rebuilt on the next view)"
        if self.deleted:
            out += f", {self.deleted} object(s) deleted from the store"
        if self.kept:
            out += f", {self.kept} object(s) left in the store"
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
    """Moves every stored object back into its row and, with commit=True, deletes the objects no row points to any
    more (see module doc); a session whose object is missing or corrupt stops the run with
    StoredObjectMissing/StoredObjectCorrupt, nothing of it lost."""
    report = MoveReport()
    sweeper = _Sweeper(conn, store, report) if commit else None
    if sweeper:
        sweeper.leftovers()
    q = lambda last: sa.select(_SESSION.c.id, _SESSION.c.file_key, _SESSION.c.content_hash).where(  # noqa: E731
        _SESSION.c.file_key.is_not(None), _SESSION.c.id > last
    )
    for rows in _batches(conn, q, batch):
        moved: list[str] = []
        for row in rows:
            data = store.get(row.file_key, row.content_hash)
            conn.execute(sa.update(_SESSION).where(_SESSION.c.id == row.id).values(file_bytes=data, file_key=None))
            moved.append(row.file_key)
            report.sessions += 1
        _after_batch(conn, sweeper, report, moved)
        if progress:
            progress(f"session files back in the database: {report.sessions}")
    q = lambda last: sa.select(_REPLAY.c.id, _REPLAY.c.data_key, _REPLAY.c.data_hash).where(  # noqa: E731
        _REPLAY.c.data_key.is_not(None), _REPLAY.c.id > last
    )
    for rows in _batches(conn, q, batch):
        moved = []
        for row in rows:
            try:
                data = store.get(row.data_key, row.data_hash)
            except StoredObjectMissing:
                conn.execute(sa.delete(_REPLAY).where(_REPLAY.c.id == row.id))
                report.replays_dropped += 1
                continue
            # data_hash stays: it names the object a crashed run may have left behind (leftovers)
            conn.execute(sa.update(_REPLAY).where(_REPLAY.c.id == row.id).values(data=data, data_key=None))
            moved.append(row.data_key)
            report.replays += 1
        _after_batch(conn, sweeper, report, moved)
        if progress:
            progress(f"replays back in the database: {report.replays}")
    return report


def _after_batch(conn: Connection, sweeper: _Sweeper | None, report: MoveReport, moved: list[str]) -> None:
    """Commits a batch of move_in and deletes its objects (commit=True), or counts them as kept (the migration)."""
    if sweeper is None:
        report.kept += len(set(moved))
        return
    conn.commit()
    for key in dict.fromkeys(moved):
        sweeper.delete_if_unreferenced(key)


class _Sweeper:
    """Deletes the session files and replays move_in has put back in the database, once no row points to them."""

    def __init__(self, conn: Connection, store: ObjectStore, report: MoveReport) -> None:
        self.conn, self.store, self.report = conn, store, report
        self._unhashed: set[str] | None = None
        inspector = sa.inspect(conn)
        columns = (
            {c["name"] for c in inspector.get_columns("session_metric_version")}
            if inspector.has_table("session_metric_version")
            else set()
        )
        self.pointers: list[tuple[sa.TableClause, sa.ColumnClause[Any]]] = [
            (_SESSION, _SESSION.c.file_key),
            (_REPLAY, _REPLAY.c.data_key),
        ] + ([(_EARLIER, _EARLIER.c.file_key)] if "file_key" in columns else [])

    def _referenced(self, key: str) -> bool:
        return any(
            self.conn.scalar(sa.select(sa.literal(1)).select_from(table).where(col == key).limit(1)) is not None
            for table, col in self.pointers
        )

    def delete_if_unreferenced(self, key: str) -> None:
        """Deletes key from the store unless a row points to it."""
        if not self._referenced(key):
            self.store.delete(key)
            self.report.deleted += 1

    def leftovers(self) -> None:
        """Deletes the objects an earlier, crashed move_in left behind: session files and replays no row points to
        whose sha256 is that of bytes a row holds in the database (content_hash of file_bytes, data_hash of data; a
        replay moved back before data_hash was kept has its bytes hashed, once, only when such an object is found)."""
        held = {
            "session": lambda digest: sa.select(_SESSION.c.id).where(
                _SESSION.c.content_hash == digest, _SESSION.c.file_bytes.is_not(None)
            ),
            "replay": lambda digest: sa.select(_REPLAY.c.id).where(
                _REPLAY.c.data_hash == digest, _REPLAY.c.data.is_not(None)
            ),
        }
        for key in list(self.store.keys()):
            kind, _, digest = key.rpartition("/")
            kind = kind.partition("/")[0]
            if not (kind in held and is_object_key(key)):
                continue
            if self.conn.scalar(held[kind](digest).limit(1)) is not None or (
                kind == "replay" and digest in self._unhashed_replays()
            ):
                self.delete_if_unreferenced(key)

    def _unhashed_replays(self) -> set[str]:
        if self._unhashed is None:
            rows = self.conn.execute(
                sa.select(_REPLAY.c.data).where(_REPLAY.c.data.is_not(None), _REPLAY.c.data_hash.is_(None))
            )
            self._unhashed = {sha256_hex(r.data) for r in rows}
        return self._unhashed
