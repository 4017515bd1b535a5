"""The object stores tests run against: the local filesystem, and S3 served by moto's server mode (a real HTTP
S3-compatible server from PyPI; no MinIO server binary is published on PyPI, Debian or npm)."""

from __future__ import annotations

import contextlib
import logging
import uuid
from collections.abc import Iterator
from pathlib import Path

from backend.storage.local import LocalStore
from backend.storage.s3 import S3Store


@contextlib.contextmanager
def s3_server() -> Iterator[str]:
    """Runs moto's S3-compatible HTTP server on a free local port; yields its endpoint URL."""
    from moto.server import ThreadedMotoServer

    logging.getLogger("werkzeug").setLevel(logging.ERROR)
    server = ThreadedMotoServer(ip_address="127.0.0.1", port=0, verbose=False)
    server.start()
    host, port = server.get_host_and_port()
    try:
        yield f"http://{host}:{port}"
    finally:
        server.stop()


def s3_store(endpoint: str) -> S3Store:
    """Returns a store on a new bucket of the server at endpoint (any access key: moto accepts all)."""
    store = S3Store.connect(
        bucket=f"coach-test-{uuid.uuid4().hex[:12]}",
        endpoint_url=endpoint,
        access_key_id="coach-test",
        secret_access_key="coach-test-secret",
    )
    store.ensure_bucket()
    return store


def local_store(root: Path) -> LocalStore:
    """Returns a store in a new folder under root."""
    return LocalStore(root / uuid.uuid4().hex[:12])
