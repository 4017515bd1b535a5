"""Shared fixtures of the benchmark tests."""

from __future__ import annotations

import json
from typing import Any

import pytest

from bench import accuracy


@pytest.fixture(scope="session")
def quick_accuracy(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The results file of `bench/accuracy.py --quick` (default settings and seeds), run once for the session: its
    per-motion rows are the ones test_accuracy_per_motion.py judges, and computing them twice cost ~45 s a run."""
    out = tmp_path_factory.mktemp("acc") / "quick.json"
    assert accuracy.main(["--quick", "--json", str(out)]) == 0
    return json.loads(out.read_text())
