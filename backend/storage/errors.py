"""Errors of the object store, answered to API clients as {"error", "detail"} like every AppError."""

from __future__ import annotations

from backend.exceptions import AppError


class StorageError(AppError):
    """The object store could not be reached or refused an operation."""

    status_code = 503


class StoredObjectMissing(StorageError):
    """An object the database points to is not in the store (deleted, or the store was not restored)."""

    status_code = 500


class StoredObjectCorrupt(StorageError):
    """An object's bytes no longer have the sha256 the database recorded."""

    status_code = 500
