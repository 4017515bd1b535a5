"""Which store this process uses: built once from the settings, replaceable by use_store()."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from backend.storage.base import ObjectStore

if TYPE_CHECKING:
    from backend.config import Settings

_store: ObjectStore | None = None


def build_store(settings: Settings) -> ObjectStore:
    """Returns the store the settings name: LocalStore under STORAGE_DIR, or S3Store on S3_BUCKET."""
    if settings.STORAGE_BACKEND == "s3":
        from backend.storage.s3 import S3Store

        return S3Store.connect(
            bucket=settings.S3_BUCKET,
            prefix=settings.S3_PREFIX,
            endpoint_url=settings.S3_ENDPOINT_URL,
            region=settings.S3_REGION,
            access_key_id=settings.S3_ACCESS_KEY_ID,
            secret_access_key=settings.S3_SECRET_ACCESS_KEY,
        )
    from backend.storage.local import LocalStore

    return LocalStore(Path(settings.storage_dir))


def get_store() -> ObjectStore:
    """Returns this process's store (built from get_settings() on first use)."""
    global _store
    if _store is None:
        from backend.config import get_settings

        _store = build_store(get_settings())
    return _store


def use_store(store: ObjectStore | None) -> None:
    """Makes `store` this process's store (None: build it again from the settings on next use)."""
    global _store
    _store = store
