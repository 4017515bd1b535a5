"""Migration 0011 and `coach-server storage`: blobs move to the store and back, in batches, resumably."""

from __future__ import annotations

import datetime as dt
import hashlib
import uuid
from collections.abc import Iterator
from typing import IO

import pytest
import sqlalchemy as sa

from backend.migrate import downgrade, upgrade
from backend.storage.base import ObjectStore, StoredObject
from backend.storage.check import check
from backend.storage.move import move_in, move_out

NOW = dt.datetime(2026, 11, 20, tzinfo=dt.UTC)
USER = sa.table("user", *(sa.column(c) for c in ("id", "email", "full_name", "role", "is_active", "created_at")))
SESSION = sa.table("exercise_session", sa.column("id"), sa.column("client_session_id", sa.Uuid),
                   *(sa.column(c) for c in ("patient_id", "started_at", "duration_s", "n_frames", "file_bytes",
                                            "file_size", "content_hash", "processing_version", "status", "created_at")),
                   sa.column("processing_params", sa.JSON))  # fmt: skip
REPLAY = sa.table("session_replay", *(sa.column(c) for c in ("id", "session_id", "version", "data", "size", "n_frames",
                                                             "duration_s", "view", "created_at")))  # fmt: skip
FILES = {i: f"session file {i} ".encode() * (100 + i) for i in range(1, 6)}


def _fill_at_0010(engine, *, bad_hash_id: int | None = None) -> None:
    with engine.begin() as conn:
        upgrade(conn, "0010")
        conn.execute(sa.insert(USER).values(id=1, email="p@x.org", full_name="P", role="patient", is_active=True,
                                            created_at=NOW))  # fmt: skip
        for sid, data in FILES.items():
            digest = "0" * 64 if sid == bad_hash_id else hashlib.sha256(data).hexdigest()
            conn.execute(sa.insert(SESSION).values(id=sid, client_session_id=uuid.uuid4(), patient_id=1,
                                                   started_at=NOW, duration_s=1.0, n_frames=30, file_bytes=data,
                                                   file_size=len(data), content_hash=digest, processing_version="",
                                                   status="processed", created_at=NOW,
                                                   processing_params={}))  # fmt: skip
        conn.execute(sa.insert(REPLAY).values(id=1, session_id=1, version="v", data=b"viser scene", size=11,
                                              n_frames=30, duration_s=1.0, view="front", created_at=NOW))  # fmt: skip


def _rows(conn):
    cols = sa.text("SELECT id, file_key, file_bytes FROM exercise_session ORDER BY id")
    return {r.id: (r.file_key, r.file_bytes) for r in conn.execute(cols)}


def test_upgrade_moves_every_blob_out_and_downgrade_brings_it_back(fresh_engine, with_store):
    _fill_at_0010(fresh_engine, bad_hash_id=5)
    with fresh_engine.begin() as conn:
        upgrade(conn, "head")
    with fresh_engine.connect() as conn:
        rows = _rows(conn)
        replay = conn.execute(sa.text("SELECT data, data_key, data_hash FROM session_replay")).one()
        report = check(conn, with_store)
    for sid in range(1, 5):
        key, blob = rows[sid]
        assert blob is None and with_store.get(key, hashlib.sha256(FILES[sid]).hexdigest()) == FILES[sid]
    assert rows[5] == (None, FILES[5]), "bytes that do not match their recorded sha256 stay where they are"
    assert replay.data is None and with_store.get(replay.data_key, replay.data_hash) == b"viser scene"
    assert report.ok and report.checked == 5 and report.in_database == 1 and report.orphans == []
    with fresh_engine.begin() as conn:
        downgrade(conn, "0010")
    with fresh_engine.connect() as conn:
        blobs = dict(conn.execute(sa.text("SELECT id, file_bytes FROM exercise_session")).all())
        assert conn.scalar(sa.text("SELECT data FROM session_replay")) == b"viser scene"
    assert blobs == FILES


class _CrashingStore(ObjectStore):
    """Wraps a store and fails on the n-th write, as a server killed mid-move would."""

    def __init__(self, store: ObjectStore, fail_at: int) -> None:
        self.store, self.fail_at, self.puts = store, fail_at, 0

    def put(self, kind: str, data: bytes) -> StoredObject:
        self.puts += 1
        if self.puts == self.fail_at:
            raise OSError("killed")
        return self.store.put(kind, data)

    def _put_file(self, key: str, file: IO[bytes], sha256: str, size: int) -> None:
        self.store._put_file(key, file, sha256, size)

    def _get(self, key: str) -> bytes:
        return self.store._get(key)

    def _open(self, key: str) -> IO[bytes]:
        return self.store._open(key)

    def exists(self, key: str) -> bool:
        return self.store.exists(key)

    def delete(self, key: str) -> None:
        self.store.delete(key)

    def keys(self) -> Iterator[str]:
        return self.store.keys()

    def describe(self) -> str:
        return self.store.describe()


def test_a_deferred_move_resumes_after_a_crash_without_repeating(fresh_engine, with_store, monkeypatch):
    _fill_at_0010(fresh_engine)
    monkeypatch.setenv("COACH_STORAGE_DEFER_MOVE", "1")
    with fresh_engine.begin() as conn:
        upgrade(conn, "head")
    assert all(key is None for key, _ in _rows(fresh_engine.connect()).values())
    seen: list[str] = []
    with fresh_engine.connect() as conn, pytest.raises(OSError, match="killed"):
        move_out(conn, _CrashingStore(with_store, fail_at=3), batch=1, commit=True, progress=seen.append)
    with fresh_engine.connect() as conn:
        done = {sid for sid, (key, _) in _rows(conn).items() if key}
    assert done == {1, 2} and seen == ["session files: 1 of 5", "session files: 2 of 5"]
    with fresh_engine.connect() as conn:
        report = move_out(conn, with_store, batch=2, commit=True)
    assert (report.sessions, report.replays) == (3, 1), "the re-run moves only what was left"
    with fresh_engine.connect() as conn:
        assert all(key and blob is None for key, blob in _rows(conn).values())
        assert check(conn, with_store).ok


def test_check_names_a_missing_and_a_corrupt_object(fresh_engine, with_store):
    _fill_at_0010(fresh_engine)
    with fresh_engine.begin() as conn:
        upgrade(conn, "head")
    with fresh_engine.connect() as conn:
        rows = _rows(conn)
        with_store.delete(rows[2][0])
        with_store.put("replay", b"an object no row points to")
        conn.execute(sa.text("UPDATE exercise_session SET content_hash = :h WHERE id = 3"), {"h": "1" * 64})
        report = check(conn, with_store)
    assert report.missing == [f"session 2: {rows[2][0]}"]
    assert report.corrupt == [f"session 3: {rows[3][0]}"]
    assert len(report.orphans) == 1 and report.orphans[0].startswith("replay/") and not report.ok


def _at_head_with_a_shared_object(engine) -> dict[int, tuple[str | None, bytes | None]]:
    """Fills the database at 0010, moves everything out, and adds session 6 with the bytes of session 1 (the same
    object); returns the rows."""
    _fill_at_0010(engine)
    with engine.begin() as conn:
        upgrade(conn, "head")
        key = _rows(conn)[1][0]
        conn.execute(sa.insert(SESSION).values(id=6, client_session_id=uuid.uuid4(), patient_id=1, started_at=NOW,
                                               duration_s=1.0, n_frames=30, file_size=len(FILES[1]),
                                               content_hash=hashlib.sha256(FILES[1]).hexdigest(),
                                               processing_version="", status="processed", created_at=NOW,
                                               processing_params={}))  # fmt: skip
        conn.execute(sa.text("UPDATE exercise_session SET file_key = :k WHERE id = 6"), {"k": key})
        return _rows(conn)


def test_move_in_deletes_each_object_once_no_row_points_to_it(fresh_engine, with_store):
    rows = _at_head_with_a_shared_object(fresh_engine)
    assert len(list(with_store.keys())) == 6, "5 session files and a replay"
    deleted_while_referenced: list[str] = []

    class Watching(_CrashingStore):
        def delete(self, key: str) -> None:
            with fresh_engine.connect() as other:
                if key in {k for k, _ in _rows(other).values()}:
                    deleted_while_referenced.append(key)
            super().delete(key)

    with fresh_engine.connect() as conn:
        report = move_in(conn, Watching(with_store, fail_at=0), batch=1, commit=True)
    assert (report.sessions, report.replays, report.deleted, report.kept) == (6, 1, 6, 0)
    assert deleted_while_referenced == [], "an object goes only once no committed row points to it"
    assert "6 object(s) deleted from the store" in report.text()
    with fresh_engine.connect() as conn:
        blobs = {sid: blob for sid, (key, blob) in _rows(conn).items() if key is None}
        after = check(conn, with_store)
        assert conn.scalar(sa.text("SELECT data FROM session_replay")) == b"viser scene"
    assert blobs == {**FILES, 6: FILES[1]} and rows[6][0] == rows[1][0]
    assert list(with_store.keys()) == [] and after.orphans == [] and after.ok


def test_move_in_after_a_crash_deletes_what_the_crashed_run_left(fresh_engine, with_store):
    _at_head_with_a_shared_object(fresh_engine)

    class DyingOnDelete(_CrashingStore):
        def delete(self, key: str) -> None:
            self.puts += 1
            if self.puts == self.fail_at:
                raise OSError("killed")
            super().delete(key)

    with fresh_engine.connect() as conn, pytest.raises(OSError, match="killed"):
        move_in(conn, DyingOnDelete(with_store, fail_at=3), batch=2, commit=True)
    with fresh_engine.connect() as conn:
        left = check(conn, with_store).orphans
        # a replay moved back by a run from before data_hash was kept: its bytes are hashed to find its object
        conn.execute(sa.text("UPDATE session_replay SET data = :d, data_key = NULL, data_hash = NULL"),
                     {"d": b"viser scene"})  # fmt: skip
        conn.commit()
    digest = hashlib.sha256(FILES[4]).hexdigest()
    assert left == [f"session/{digest[:2]}/{digest}"], "killed at the 3rd delete: session 4's object"
    with fresh_engine.connect() as conn:
        report = move_in(conn, with_store, batch=2, commit=True)
        after = check(conn, with_store)
    assert (report.sessions, report.replays, report.deleted) == (2, 0, 4), "4's and the replay's, then 5's and 1's"
    assert list(with_store.keys()) == [] and after.orphans == [] and after.ok
    with fresh_engine.connect() as conn:
        assert {sid: blob for sid, (_, blob) in _rows(conn).items()} == {**FILES, 6: FILES[1]}


def test_the_downgrade_migration_keeps_the_objects_it_cannot_delete_safely(fresh_engine, with_store):
    _fill_at_0010(fresh_engine)
    with fresh_engine.begin() as conn:
        upgrade(conn, "head")
    with fresh_engine.begin() as conn:
        report = move_in(conn, with_store)
    assert (report.sessions, report.deleted, report.kept) == (5, 0, 6)
    assert len(list(with_store.keys())) == 6, "a rollback of the migration must find every object still there"
