"""The local filesystem store: one file per object under a root folder (by default the server's data folder)."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO

from backend.storage.base import CHUNK, ObjectStore, file_sha256, is_object_key
from backend.storage.errors import StorageError, StoredObjectMissing


class LocalStore(ObjectStore):
    """Objects as files root/kind/ab/<sha256>; written to a temporary file, fsynced, then renamed into place."""

    name = "local"
    verify_before_sending = True  # a second read of a local file is cheap: a corrupt one is refused before sending

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root).resolve()

    def _path(self, key: str) -> Path:
        if not is_object_key(key):
            raise StorageError(f"invalid object key {key!r}")
        return self.root / key

    def _put_file(self, key: str, file: IO[bytes], sha256: str, size: int) -> None:
        path = self._path(key)
        try:
            if path.is_file() and path.stat().st_size == size:
                with path.open("rb") as there:
                    if file_sha256(there)[0] == sha256:
                        return  # already there: content-addressed
            path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-")
            try:
                with os.fdopen(fd, "wb") as f:
                    shutil.copyfileobj(file, f, CHUNK)
                    f.flush()
                    os.fsync(f.fileno())
                os.replace(tmp, path)
            except BaseException:
                Path(tmp).unlink(missing_ok=True)
                raise
            dir_fd = os.open(path.parent, os.O_RDONLY)
            try:
                os.fsync(dir_fd)
            finally:
                os.close(dir_fd)
        except OSError as exc:
            raise StorageError(f"cannot write {key} under {self.root}: {exc.strerror or exc}") from None

    def _get(self, key: str) -> bytes:
        try:
            return self._path(key).read_bytes()
        except FileNotFoundError:
            raise StoredObjectMissing(f"stored object {key} is missing from {self.root}") from None
        except OSError as exc:
            raise StorageError(f"cannot read {key} under {self.root}: {exc.strerror or exc}") from None

    def _open(self, key: str) -> IO[bytes]:
        try:
            return self._path(key).open("rb")
        except FileNotFoundError:
            raise StoredObjectMissing(f"stored object {key} is missing from {self.root}") from None
        except OSError as exc:
            raise StorageError(f"cannot read {key} under {self.root}: {exc.strerror or exc}") from None

    def exists(self, key: str) -> bool:
        """Returns whether key is in the store."""
        return self._path(key).is_file()

    def delete(self, key: str) -> None:
        """Removes key (nothing happens when it is absent)."""
        self._path(key).unlink(missing_ok=True)

    def keys(self) -> Iterator[str]:
        """Yields every object key in the store."""
        if not self.root.is_dir():
            return
        for path in self.root.glob("*/*/*"):
            key = path.relative_to(self.root).as_posix()
            if path.is_file() and is_object_key(key):
                yield key

    def describe(self) -> str:
        """Returns the folder."""
        return f"local folder {self.root}"
