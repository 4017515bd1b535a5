"""Run by tests/test_deployables.py only, named on its command line (the file's name is no test_*.py: the suite's own
runs, where both sides can be imported, never collect it): inside one deployable's environment (its lock file, its
wheel and its tests' tools), from a copy of tests/ beside no source of the repository. Each test says that the side's
tests in that run import the installed distribution, and that the other side's code and packages cannot be imported
there."""

from __future__ import annotations

import importlib
import sys
import sysconfig
from pathlib import Path

import pytest


def _installed(module: str) -> Path:
    """Returns module's file after asserting that it comes from this environment's site-packages."""
    path = Path(importlib.import_module(module).__file__ or "").resolve()
    site = Path(sysconfig.get_paths()["purelib"]).resolve()
    assert path.is_relative_to(site), f"{module} is imported from {path}, not from the installed {site}"
    return path


def _absent(module: str) -> None:
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module(module)
    assert module not in sys.modules


def test_the_agent_alone() -> None:
    for module in ("kinect_agent.cli", "kinect_agent.upload", "kinect_agent.processing.pipeline", "numba"):
        _installed(module)
    for module in ("backend", "frontend", "migrations", "fastapi", "sqlalchemy", "uvicorn", "pydantic_settings"):
        _absent(module)


def test_the_server_alone() -> None:
    for module in ("backend.main", "frontend.pages", "migrations", "kinect_agent.recording", "kinect_agent.formats"):
        _installed(module)
    for module in ("kinect_agent.cli", "kinect_agent.upload", "kinect_agent.capture", "kinect_agent.live", "numba"):
        _absent(module)
