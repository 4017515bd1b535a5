"""The records tests use a new store of each back-end (tests/backend/storage/conftest.py)."""

from tests.backend.storage.conftest import any_store, with_store  # noqa: F401
