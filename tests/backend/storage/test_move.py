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
from backend.storage.move import move_out

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
