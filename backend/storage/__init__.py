"""Object storage of session files and replays: content-addressed (sha256), atomic writes, hash-checked reads.

`get_store()` returns the store this process uses (built once from the settings: the local filesystem under the
server's data folder by default, or an S3-compatible bucket); `use_store()` replaces it (tests, tools).
"""

from __future__ import annotations

from backend.storage.base import ObjectStore, StoredObject, object_key
from backend.storage.errors import StorageError, StoredObjectCorrupt, StoredObjectMissing
from backend.storage.factory import build_store, get_store, use_store

__all__ = [
    "ObjectStore",
    "StorageError",
    "StoredObject",
    "StoredObjectCorrupt",
    "StoredObjectMissing",
    "build_store",
    "get_store",
    "object_key",
    "use_store",
]
