"""Each storage test runs on both back-ends: the local filesystem and S3 (moto's server mode)."""

from __future__ import annotations

import pytest

from tests.backend.object_stores import local_store, s3_store


@pytest.fixture(params=["local", "s3"])
def any_store(request, tmp_path):
    """A new, empty store of each back-end (S3: a new bucket on the run's moto server)."""
    if request.param == "s3":
        return s3_store(request.getfixturevalue("_s3_endpoint"))
    return local_store(tmp_path)


@pytest.fixture
def with_store(any_store):
    """Makes any_store the server's store for the test, then restores the run's store."""
    from backend.storage import factory

    before = factory._store
    factory.use_store(any_store)
    yield any_store
    factory.use_store(before)
