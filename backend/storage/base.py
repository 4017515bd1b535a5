"""The object store interface: put bytes (or a file, a chunk at a time) under their sha256, read them back checked,
list and delete keys."""

from __future__ import annotations

import hashlib
import io
import os
import re
import tempfile
from abc import ABC, abstractmethod
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from backend.storage.errors import StoredObjectCorrupt

KINDS = ("session", "replay", "detail", "export", "archive")
_KEY = re.compile(r"^(session|replay|detail|export|archive)/[0-9a-f]{2}/[0-9a-f]{64}$")
CHUNK = 1024 * 1024  # bytes read at a time from a file being stored or checked


def sha256_hex(data: bytes) -> str:
    """Returns the SHA-256 of data as 64 lowercase hex digits."""
    return hashlib.sha256(data).hexdigest()


def file_sha256(file: IO[bytes]) -> tuple[str, int]:
    """Returns (SHA-256 as 64 hex digits, size in bytes) of a file read from where it is to its end, a CHUNK at a
    time."""
    digest, size = hashlib.sha256(), 0
    while chunk := file.read(CHUNK):
        digest.update(chunk)
        size += len(chunk)
    return digest.hexdigest(), size


def object_key(kind: str, sha256: str) -> str:
    """Returns the key of an object of `kind` ("session" file, "replay", session "detail", "export" download,
    patient's "archive") with this sha256: kind/ab/abcd…."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    return f"{kind}/{sha256[:2]}/{sha256}"


def is_object_key(key: str) -> bool:
    """Returns whether key has the form object_key makes (no path traversal, nothing else)."""
    return bool(_KEY.match(key))


@dataclass(frozen=True)
class StoredObject:
    """Where an object went: its key, the sha256 of its bytes (64 hex digits) and its size in bytes."""

    key: str
    sha256: str
    size: int


class ObjectStore(ABC):
    """A content-addressed store: the same bytes always get the same key, so writing twice is harmless."""

    name: str  # "local" or "s3", shown by `coach-server storage check`

    def put(self, kind: str, data: bytes) -> StoredObject:
        """Stores data atomically (a reader sees all of it or nothing) and returns its key and hash."""
        digest = sha256_hex(data)
        key = object_key(kind, digest)
        self._put_file(key, io.BytesIO(data), digest, len(data))
        return StoredObject(key=key, sha256=digest, size=len(data))

    def put_file(self, kind: str, file: IO[bytes]) -> StoredObject:
        """Stores the bytes of a seekable file, from its start, atomically as put does, reading it a CHUNK at a time
        (once to hash it, once to write it): a file of any size costs no more memory than a chunk. Returns its key
        and hash."""
        file.seek(0)
        digest, size = file_sha256(file)
        key = object_key(kind, digest)
        file.seek(0)
        self._put_file(key, file, digest, size)
        return StoredObject(key=key, sha256=digest, size=size)

    # whether stream() reads an object through once to check it before its first chunk: cheap on a local disk; on
    # a remote store it would fetch every byte twice, so there stream() checks on the way and fails after the end
    verify_before_sending = False

    def get(self, key: str, sha256: str) -> bytes:
        """Returns the bytes of key; raises StoredObjectMissing, or StoredObjectCorrupt when their sha256 differs."""
        data = self._get(key)
        _require(key, sha256_hex(data), sha256)
        return data

    def read_chunks(self, key: str, sha256: str) -> Iterator[bytes]:
        """Returns an iterator over the bytes of key, a CHUNK at a time, hashing them on the way: StoredObjectMissing
        is raised here, before any chunk; StoredObjectCorrupt after the last chunk when their sha256 differs (so a
        reader keeps what it read aside until the end: verify, copy_to)."""
        return _checked(key, sha256, self._open(key))

    def verify(self, key: str, sha256: str) -> None:
        """Reads key through a CHUNK at a time; raises StoredObjectMissing, or StoredObjectCorrupt when its sha256
        differs."""
        for _ in self.read_chunks(key, sha256):
            pass

    def stream(self, key: str, sha256: str) -> Iterator[bytes]:
        """Returns the bytes of key as chunks to send: where verify_before_sending (local), a missing or corrupt object
        raises here, before anything is sent; elsewhere (S3) a missing one raises here and a corrupt one raises
        StoredObjectCorrupt after its last chunk, which a sender turns into an aborted transfer."""
        if self.verify_before_sending:
            self.verify(key, sha256)
            return self.read_chunks(key, sha256)
        return _holding_last(self.read_chunks(key, sha256))

    def copy_to(self, key: str, sha256: str, path: str | Path) -> int:
        """Writes the bytes of key to path a CHUNK at a time, through a temporary file beside it that replaces path
        only once its sha256 is checked: a missing or corrupt object raises and leaves path as it was. Returns the
        bytes written."""
        path = Path(path)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
        try:
            size = 0
            with os.fdopen(fd, "wb") as f:
                for chunk in self.read_chunks(key, sha256):
                    f.write(chunk)
                    size += len(chunk)
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        return size

    def check(self, key: str, sha256: str) -> str | None:
        """Returns None when key holds bytes of this sha256, else "missing" or "corrupt" (read a CHUNK at a time)."""
        from backend.storage.errors import StoredObjectMissing

        try:
            self.verify(key, sha256)
        except StoredObjectMissing:
            return "missing"
        except StoredObjectCorrupt:
            return "corrupt"
        return None

    @abstractmethod
    def _put_file(self, key: str, file: IO[bytes], sha256: str, size: int) -> None:
        """Writes `size` bytes read from the file's position (their sha256 given) under key, atomically, a chunk at a
        time; nothing when key already holds them."""

    @abstractmethod
    def _get(self, key: str) -> bytes:
        """Returns the bytes of key or raises StoredObjectMissing."""

    @abstractmethod
    def _open(self, key: str) -> IO[bytes]:
        """Returns a readable binary stream of key's bytes (the caller closes it) or raises StoredObjectMissing; its
        read errors are StorageError."""

    @abstractmethod
    def exists(self, key: str) -> bool:
        """Returns whether key is in the store."""

    @abstractmethod
    def delete(self, key: str) -> None:
        """Removes key (nothing happens when it is absent)."""

    @abstractmethod
    def keys(self) -> Iterator[str]:
        """Yields every object key in the store (any order)."""

    @abstractmethod
    def describe(self) -> str:
        """Returns where the objects are, in words (a folder, or a bucket and endpoint)."""


def _require(key: str, actual: str, sha256: str) -> None:
    """Raises StoredObjectCorrupt when the sha256 read (actual) is not the one the database recorded."""
    if actual != sha256:
        raise StoredObjectCorrupt(
            f"stored object {key} is corrupt: its sha256 is {actual[:16]}…, the database recorded {sha256[:16]}…"
        )


def _checked(key: str, sha256: str, stream: IO[bytes]) -> Iterator[bytes]:
    """Yields the stream's bytes a CHUNK at a time, closes it, then raises StoredObjectCorrupt when their sha256 is
    not sha256."""
    digest = hashlib.sha256()
    with stream:
        while chunk := stream.read(CHUNK):
            digest.update(chunk)
            yield chunk
    _require(key, digest.hexdigest(), sha256)


def _holding_last(chunks: Iterator[bytes]) -> Iterator[bytes]:
    """Yields chunks one behind: the last one only once the iterator ended without raising (its check passed)."""
    held: bytes | None = None
    for chunk in chunks:
        if held is not None:
            yield held
        held = chunk
    if held is not None:
        yield held
