"""The kept archive leaves the object store a chunk at a time, its sha256 checked on the way: the API streams it and
the CLI copies it, both in memory far below the zip's size; a corrupt zip is refused before the first byte on the
filesystem, aborts the transfer short of Content-Length on S3, and never becomes the CLI's file."""

from __future__ import annotations

import datetime as dt
import hashlib
import io
import json
import tracemalloc
from dataclasses import dataclass, field
from typing import Any

import anyio
import numpy as np
import pytest

from backend.records import prepared_archive
from backend.records.commands import _write_archive
from backend.records.models import PatientArchive
from backend.storage import factory, get_store
from backend.storage.errors import StoredObjectCorrupt
from backend.storage.local import LocalStore
from backend.storage.s3 import S3Store
from tests.backend.object_stores import local_store
from tests.backend.session_rows import store_session

MIB = 2**20


@dataclass
class _Sent:
    """What an ASGI server would have sent: the status, headers, body size and hash, whether the body ended."""

    status: int = 0
    headers: dict[str, str] = field(default_factory=dict)
    size: int = 0
    digest: Any = field(default_factory=hashlib.sha256)
    ended: bool = False
    head: bytes = b""  # the body's first KiB
    error: BaseException | None = None


def _get(app, path: str, headers: dict[str, str]) -> _Sent:
    """Runs one GET through the ASGI app as a server would, keeping no body: counts and hashes it, and records an
    exception raised after the response started (a server then drops the connection)."""
    sent = _Sent()
    target, _, query = path.partition("?")
    scope = {"type": "http", "asgi": {"version": "3.0", "spec_version": "2.4"}, "http_version": "1.1",
             "method": "GET", "scheme": "http", "path": target, "raw_path": target.encode(),
             "query_string": query.encode(), "root_path": "", "client": ("127.0.0.1", 1), "server": ("test", 80),
             "headers": [(k.lower().encode(), v.encode()) for k, v in headers.items()]}  # fmt: skip

    async def receive() -> dict[str, Any]:
        return {"type": "http.request", "body": b"", "more_body": False}

    async def send(message: dict[str, Any]) -> None:
        if message["type"] == "http.response.start":
            sent.status = message["status"]
            sent.headers = {k.decode(): v.decode() for k, v in message["headers"]}
        elif message["type"] == "http.response.body":
            sent.head += message.get("body", b"")[: 1024 - len(sent.head)]
            sent.size += len(message.get("body", b""))
            sent.digest.update(message.get("body", b""))
            sent.ended = not message.get("more_body", False)

    async def run() -> None:
        try:
            await app(scope, receive, send)
        except Exception as exc:  # noqa: BLE001 - what a server sees after the response started
            if not sent.status:
                raise
            sent.error = exc

    anyio.run(run)
    return sent


def _large_archive(db_session, settings, make_user, exercise, sessions: int) -> tuple[Any, PatientArchive]:
    """(patient, kept archive) of `sessions` sessions of 2 MiB of random bytes each (the zip is as large)."""
    patient = make_user("patient")
    rng, first = np.random.default_rng(20261128), dt.datetime(2026, 10, 1, tzinfo=dt.UTC)
    for k in range(sessions):
        obj = get_store().put("session", rng.bytes(2 * MIB))
        row = store_session(db_session, patient, exercise, first + dt.timedelta(days=k), data=b"")
        row.file_bytes, row.file_key, row.content_hash, row.file_size = None, obj.key, obj.sha256, obj.size
    db_session.flush()
    prepared_archive.run(db_session=db_session, patient_id=patient.id, requested_by="the patient", settings=settings)
    kept = prepared_archive.kept_archive(db_session=db_session, patient_id=patient.id)
    assert kept is not None and kept.size > 2 * sessions * MIB, kept
    return patient, kept


@pytest.fixture
def local_only(tmp_path):
    """The local store as the server's (moto's S3 server runs in this process and holds what it serves in its own
    memory, so memory is measured on the filesystem; test_the_zip_is_read_in_chunks_on_both_backends covers S3)."""
    before = factory._store
    factory.use_store(local_store(tmp_path / "store"))
    yield
    factory.use_store(before)


def test_the_api_streams_a_large_archive_in_bounded_memory(app, db_session, settings, make_user, exercise,
                                                          auth_headers, local_only):  # fmt: skip
    patient, kept = _large_archive(db_session, settings, make_user, exercise, sessions=12)
    url = f"/api/v1/patients/{patient.id}/archive?sha256={kept.data_hash}"
    tracemalloc.start()
    try:
        sent = _get(app, url, auth_headers(patient))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert sent.status == 200 and sent.ended and sent.error is None, sent
    assert sent.size == kept.size and sent.digest.hexdigest() == kept.data_hash
    said = f"the download peaked at {peak / MIB:.1f} MiB for a {kept.size / MIB:.1f} MiB zip"
    assert peak < kept.size / 4, said
    assert sent.headers["content-length"] == str(kept.size) and sent.headers["x-archive-sha256"] == kept.data_hash


def test_the_cli_copies_a_large_archive_in_bounded_memory(db_session, settings, make_user, exercise, tmp_path,
                                                          local_only):  # fmt: skip
    patient, kept = _large_archive(db_session, settings, make_user, exercise, sessions=12)
    out = tmp_path / "archive.zip"
    tracemalloc.start()
    try:
        said = _write_archive(db_session, patient, "admin boss@clinic.org", out)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert "still current" in said and out.stat().st_size == kept.size, said
    assert hashlib.sha256(out.read_bytes()).hexdigest() == kept.data_hash
    assert peak < kept.size / 4, f"the copy peaked at {peak / MIB:.1f} MiB for a {kept.size / MIB:.1f} MiB zip"


def _corrupt(store, key: str, data: bytes) -> None:
    """Replaces the object's bytes behind the database's back (bit rot, a bad restore)."""
    if isinstance(store, LocalStore):
        (store.root / key).write_bytes(data)
    else:
        assert isinstance(store, S3Store)
        store.client.put_object(Bucket=store.bucket, Key=store._name(key), Body=data)


def test_the_zip_is_read_in_chunks_on_both_backends(any_store, tmp_path):
    data = np.random.default_rng(7).bytes(2 * MIB + 123)
    obj = any_store.put_file("archive", io.BytesIO(data))
    chunks = list(any_store.stream(obj.key, obj.sha256))
    assert len(chunks) == 3 and b"".join(chunks) == data
    assert any_store.copy_to(obj.key, obj.sha256, tmp_path / "a.zip") == len(data)
    assert (tmp_path / "a.zip").read_bytes() == data


def test_a_corrupt_archive_is_refused_before_sending_on_the_filesystem_and_aborted_on_s3(any_store, tmp_path):
    data = np.random.default_rng(8).bytes(3 * MIB)
    obj = any_store.put("archive", data)
    _corrupt(any_store, obj.key, data[: 2 * MIB] + b"rot")
    if isinstance(any_store, LocalStore):
        with pytest.raises(StoredObjectCorrupt, match="is corrupt"):
            any_store.stream(obj.key, obj.sha256)  # before the first chunk
    else:
        chunks = any_store.stream(obj.key, obj.sha256)
        assert len(next(chunks)) == MIB  # sent on the way …
        with pytest.raises(StoredObjectCorrupt, match="is corrupt"):
            list(chunks)  # … and the transfer fails at its end
    (tmp_path / "out").mkdir()
    with pytest.raises(StoredObjectCorrupt, match="is corrupt"):
        any_store.copy_to(obj.key, obj.sha256, tmp_path / "out" / "a.zip")
    assert list((tmp_path / "out").iterdir()) == [], "the copy of a corrupt object left a file"


def test_a_corrupt_archive_download_answers_500_or_aborts(app, db_session, settings, make_user, exercise,
                                                          auth_headers, with_store, tmp_path):  # fmt: skip
    patient, kept = _large_archive(db_session, settings, make_user, exercise, sessions=1)
    rot = np.random.default_rng(9).bytes(kept.size)  # as many bytes as the zip: only the hash tells
    _corrupt(with_store, kept.data_key, rot)
    out = tmp_path / "cli.zip"
    with pytest.raises(StoredObjectCorrupt):
        _write_archive(db_session, patient, "admin boss@clinic.org", out)
    assert not out.exists() and not list(tmp_path.glob(".cli.zip.*")), "the CLI left a file of a corrupt archive"
    sent = _get(app, f"/api/v1/patients/{patient.id}/archive?sha256={kept.data_hash}", auth_headers(patient))
    if isinstance(with_store, LocalStore):
        assert sent.status == 500 and sent.error is None and sent.ended, sent
        assert json.loads(sent.head)["error"] == "StoredObjectCorrupt", sent.head[:200]
    else:  # headers went out before the mismatch was known: the body stops short, the server drops the connection
        cause = sent.error.__cause__ if isinstance(sent.error, RuntimeError) else sent.error  # "already started"
        assert sent.status == 200 and isinstance(cause, StoredObjectCorrupt) and not sent.ended, sent
        assert sent.size < int(sent.headers["content-length"]) == kept.size, "the last chunk went out unchecked"
