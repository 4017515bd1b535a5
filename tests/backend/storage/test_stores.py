"""The two object stores behave the same: content-addressed, atomic, hash-checked, clear errors."""

from __future__ import annotations

import hashlib
import tempfile

import pytest

from backend.storage import StoredObjectCorrupt, StoredObjectMissing, object_key
from backend.storage.errors import StorageError
from backend.storage.local import LocalStore


def test_put_then_get_returns_the_bytes_under_their_sha256(any_store):
    data = b"session bytes \x00\x01" * 1000
    obj = any_store.put("session", data)
    digest = hashlib.sha256(data).hexdigest()
    assert (obj.key, obj.sha256, obj.size) == (object_key("session", digest), digest, len(data))
    assert obj.key == f"session/{digest[:2]}/{digest}"
    assert any_store.get(obj.key, digest) == data
    assert any_store.put("session", data) == obj  # the same bytes: the same key, written once
    assert list(any_store.keys()) == [obj.key]


def test_a_file_put_a_chunk_at_a_time_is_stored_as_its_bytes_would_be(any_store):
    data = bytes(range(256)) * (3 * 2**12 + 7)  # 3 MiB and some: several chunks (base.CHUNK), the last one short
    with tempfile.TemporaryFile() as file:
        file.write(data)  # left at its end: put_file stores it from its start
        obj = any_store.put_file("archive", file)
        digest = hashlib.sha256(data).hexdigest()
        assert (obj.key, obj.sha256, obj.size) == (object_key("archive", digest), digest, len(data))
        assert any_store.get(obj.key, digest) == data
        assert any_store.put("archive", data) == obj == any_store.put_file("archive", file), "the same object"
    assert list(any_store.keys()) == [obj.key]


def test_a_missing_object_is_a_typed_error(any_store):
    key = object_key("session", "ab" * 32)
    with pytest.raises(StoredObjectMissing, match=f"stored object {key} is missing"):
        any_store.get(key, "ab" * 32)
    assert any_store.check(key, "ab" * 32) == "missing" and not any_store.exists(key)


def test_bytes_that_changed_in_the_store_are_reported_corrupt(any_store):
    obj = any_store.put("replay", b"the original recording")
    if isinstance(any_store, LocalStore):
        (any_store.root / obj.key).write_bytes(b"bit rot")
    else:
        any_store.client.put_object(Bucket=any_store.bucket, Key=obj.key, Body=b"bit rot")
    with pytest.raises(StoredObjectCorrupt, match="is corrupt: its sha256 is"):
        any_store.get(obj.key, obj.sha256)
    assert any_store.check(obj.key, obj.sha256) == "corrupt"
    any_store.put("replay", b"the original recording")  # writing the bytes again repairs it
    assert any_store.get(obj.key, obj.sha256) == b"the original recording"


def test_delete_removes_and_tolerates_absence(any_store):
    obj = any_store.put("session", b"x" * 10)
    any_store.delete(obj.key)
    any_store.delete(obj.key)
    assert not any_store.exists(obj.key) and list(any_store.keys()) == []


def test_keys_outside_the_scheme_are_refused(any_store):
    with pytest.raises(StorageError, match="invalid object key"):
        any_store.get("../../etc/passwd", "0" * 64)


def test_local_writes_leave_no_temporary_file(tmp_path):
    store = LocalStore(tmp_path)
    for i in range(5):
        store.put("session", bytes([i]) * 100)
    assert sorted(p.name.startswith(".tmp-") for p in tmp_path.rglob("*") if p.is_file()) == [False] * 5


def test_an_unreachable_s3_endpoint_is_a_storage_error():
    from backend.storage.s3 import S3Store

    store = S3Store.connect(bucket="coach-none", endpoint_url="http://127.0.0.1:9", access_key_id="a",
                            secret_access_key="b")  # fmt: skip
    store.client.meta.config.retries = {"max_attempts": 1}
    with pytest.raises(StorageError, match="cannot read session/"):
        store.get(object_key("session", "cd" * 32), "cd" * 32)
