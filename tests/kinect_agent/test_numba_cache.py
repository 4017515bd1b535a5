"""A read-only install: numba cannot write `__pycache__` beside the agent's modules nor the user's cache folder (a
service user without a home folder). The agent still imports, compiles its kernels once into the fallback folder
(kinect_agent.numba_cache), says where, and a second process loads them from there."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from kinect_agent.numba_cache import TEMPORARY_PREFIX, _own_writable_folder
from kinect_agent.processing import _ukf_numba

pytestmark = pytest.mark.skipif(not _ukf_numba.AVAILABLE, reason="numba is not installed (server-only environment)")
AGENT = Path(__file__).resolve().parents[2] / "kinect_agent"

CHILD = """
import json
import numpy as np
from kinect_agent.body import _rotations_numba
from kinect_agent.live.warmup import cache_folders, kernel_counts, where_cached

quats = np.empty((2, 4))
_rotations_numba.matrix_to_quat(np.broadcast_to(np.eye(3), (2, 3, 3)).copy(), quats)
print(json.dumps({**kernel_counts(), "folders": cache_folders(), "where": where_cached(cache_folders()),
                  "quat": quats[0].tolist()}))
"""


def _read_only_install(tmp_path: Path) -> Path:
    """Returns a copy of the agent's package in which no `__pycache__` can be made (a file of that name in each
    folder: unwritable even for root, as a read-only install is for its users)."""
    src = tmp_path / "install"
    shutil.copytree(AGENT, src / "kinect_agent", ignore=shutil.ignore_patterns("__pycache__", "files"))
    for folder in [src / "kinect_agent", *(src / "kinect_agent").rglob("*")]:
        if folder.is_dir():
            (folder / "__pycache__").write_text("not a folder")
    return src


def _run(src: Path, tmp_path: Path, **env: str) -> tuple[dict[str, Any], str]:
    """Runs CHILD on the install src for a user whose home folder cannot be made (under a file); returns its JSON
    line and its stderr."""
    (tmp_path / "a file").write_text("")
    no_home = str(tmp_path / "a file" / "home")
    base = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "KINECT_AGENT_HOME", "PYTHONPATH")}
    done = subprocess.run([sys.executable, "-c", CHILD], cwd=src, capture_output=True, text=True, timeout=300,
                          env={**base, "HOME": no_home, "XDG_CACHE_HOME": no_home, "PYTHONPATH": str(src),
                               "PYTHONDONTWRITEBYTECODE": "1", **env})  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1]), done.stderr


def test_a_read_only_install_caches_in_the_agents_home_and_a_second_process_loads_it(tmp_path):
    src, home = _read_only_install(tmp_path), tmp_path / "agent home"
    first, _ = _run(src, tmp_path, KINECT_AGENT_HOME=str(home))
    assert first["cache_misses"] >= 1 and first["quat"] == [1.0, 0.0, 0.0, 0.0], first
    assert first["folders"] and all(f.startswith(str(home / "numba")) for f in first["folders"]), first
    assert str(home / "numba") in str(first["where"]) and "temporary" not in str(first["where"]), first
    second, _ = _run(src, tmp_path, KINECT_AGENT_HOME=str(home))
    assert second["cache_misses"] == 0 and second["cache_hits"] >= 1, second


def test_without_an_agent_home_the_cache_is_a_temporary_folder_and_the_message_says_so(tmp_path):
    src, temporary = _read_only_install(tmp_path), tmp_path / "tmp"
    temporary.mkdir()
    first, _ = _run(src, tmp_path, TMPDIR=str(temporary))
    assert all(f.startswith(str(temporary / TEMPORARY_PREFIX)) for f in first["folders"]), first
    assert "a temporary folder" in str(first["where"]) and "KINECT_AGENT_HOME" in str(first["where"]), first
    second, _ = _run(src, tmp_path, TMPDIR=str(temporary))
    assert second["cache_misses"] == 0 and second["cache_hits"] >= 1, second


def test_a_temporary_folder_others_can_write_is_not_used_and_the_kernels_still_run(tmp_path):
    src, temporary = _read_only_install(tmp_path), tmp_path / "tmp"
    planted = temporary / f"{TEMPORARY_PREFIX}{os.getuid()}"
    planted.mkdir(parents=True)
    planted.chmod(0o777)  # made by someone else beforehand: its pickled files must not be loaded
    found, stderr = _run(src, tmp_path, TMPDIR=str(temporary))
    assert found["quat"] == [1.0, 0.0, 0.0, 0.0] and found["folders"] == [], found
    assert "no writable folder" in stderr and "compiled in each process" in stderr, stderr
    assert stderr.count("numba's cache") == 1, stderr  # said once, not per kernel module
    assert list(planted.iterdir()) == []


def test_the_fallback_folder_is_made_for_this_user_alone(tmp_path):
    assert _own_writable_folder(tmp_path / "new" / "numba")
    assert (tmp_path / "new" / "numba").stat().st_mode & 0o777 == 0o700
    (tmp_path / "shared").mkdir()
    (tmp_path / "shared").chmod(0o775)
    assert not _own_writable_folder(tmp_path / "shared")
    (tmp_path / "a file").write_text("")
    assert not _own_writable_folder(tmp_path / "a file")
