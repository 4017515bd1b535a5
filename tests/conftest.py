"""Shared test fixtures: where the real recordings live, and a fixed random generator."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from kinect_agent.blas_threads import one_blas_thread

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("COACH_SHARED_DIR", REPO.parent / "shared"))
DATA = SHARED / "data"
REFERENCE = SHARED / "reference"
# What reaches the suite's database (COACH_TEST_DATABASE_URL): the fixture that names it (tests/backend/conftest.py;
# engine, db_session, client, fresh_engine ... build on it) and the browser tests' server (tests/frontend/conftest.py).
DATABASE_FIXTURES = frozenset({"test_database_url", "live_server"})
DATABASE_VARIABLE = "COACH_TEST_DATABASE_URL"
# The tests that never open the database run once (scripts/test.sh): those below these folders in the PostgreSQL
# pass, the others in the SQLite pass, so that the two passes end together (CPU s of each folder: bench/README.md,
# "CI time").
ONCE_ON_POSTGRESQL = ("tests/kinect_agent/analysis/", "tests/backend/session_texts/", "tests/kinect_agent/sources/",
                      "tests/kinect_agent/evaluation/")  # fmt: skip


@pytest.hookimpl(tryfirst=True)  # before -m selects on the markers
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Marks "database" each test that opens the suite's database: one that uses a fixture of DATABASE_FIXTURES,
    and every test of a module that reads DATABASE_VARIABLE itself; marks "once_on_postgresql" each other test below
    ONCE_ON_POSTGRESQL."""
    reads_variable: dict[Path, bool] = {}
    for item in items:
        module = item.path
        if module not in reads_variable:
            reads_variable[module] = DATABASE_VARIABLE in module.read_text(encoding="utf-8")
        if reads_variable[module] or DATABASE_FIXTURES & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.database)
        elif module.is_relative_to(REPO) and module.relative_to(REPO).as_posix().startswith(ONCE_ON_POSTGRESQL):
            item.add_marker(pytest.mark.once_on_postgresql)


@pytest.fixture(scope="session", autouse=True)
def _one_blas_thread() -> None:
    """BLAS on one thread for the whole run, as the agent and the server run it (kinect_agent.blas_threads). Else a
    test's speed depended on whether an earlier test had created the app (create_app sets it for the process): the
    online filter alone stepped 10x slower on a busy machine (628 frames: 21.6 s instead of 2.2 s, 2026-11-27)."""
    one_blas_thread()


@pytest.fixture
def data_dir() -> Path:
    """The public recordings in ../shared/data; tests that need them skip only when it is absent (never in CI)."""
    if not DATA.is_dir():
        if os.environ.get("CI"):
            pytest.fail(f"{DATA} is missing; CI must have ../shared beside the repository")
        pytest.skip(f"{DATA} not present")
    return DATA


@pytest.fixture
def reference_dir() -> Path:
    """The paper's tables in ../shared/reference."""
    if not REFERENCE.is_dir():
        if os.environ.get("CI"):
            pytest.fail(f"{REFERENCE} is missing; CI must have ../shared beside the repository")
        pytest.skip(f"{REFERENCE} not present")
    return REFERENCE


@pytest.fixture
def rng() -> np.random.Generator:
    """A generator with a fixed seed, so numeric tests repeat exactly."""
    return np.random.default_rng(20261122)
