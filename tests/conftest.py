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
