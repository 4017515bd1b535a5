"""Pinned third-party browser assets from npm: MediaPipe Tasks Vision (the browser's WebAssembly runtime), the
BlazePose landmarker models packed as `.task` bundles (the browser and the agent's Python runtime load the same files)
and plotly.js (the pages' charts).

`lock.json` pins every npm tarball (exact version, sha512 integrity) and the SHA-256 of every `.task` built from
them; `python -m kinect_agent.vendor.install` fetches, checks and unpacks them into the git-ignored `files/`. The
server serves `lock.json`'s "serve" table, one directory of it at /static/vendor/<directory>/
(frontend/vendor_assets.py); nothing is fetched at run time.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
LOCK_PATH = HERE / "lock.json"
FILES = HERE / "files"  # git-ignored; made by kinect_agent.vendor.install
MODELS = ("lite", "full")
INSTALL_HINT = "run `python -m kinect_agent.vendor.install` (the README's set-up does)"


class VendorError(RuntimeError):
    """A pinned asset is missing, does not match its pinned hash, or cannot be fetched."""


@dataclass(frozen=True)
class ModelInfo:
    """What a session header records about the pose model: file name, what it is, its pinned SHA-256, and the
    npm package version its weights come from."""

    name: str
    model: str
    sha256: str
    source: str

    def to_dict(self) -> dict[str, str]:
        """Returns the fields as JSON-ready data."""
        return {"name": self.name, "model": self.model, "sha256": self.sha256, "source": self.source}


def load_lock(path: Path = LOCK_PATH) -> dict[str, Any]:
    """Returns the parsed lock file."""
    return json.loads(path.read_text(encoding="utf-8"))


def package_dir(name: str) -> Path:
    """Returns where the npm package `name` (e.g. "@mediapipe/pose") is unpacked."""
    return FILES / "npm" / name


def served_directories(lock: dict[str, Any] | None = None) -> list[str]:
    """Returns the directories served below /static/vendor/ ("mediapipe", "plotly")."""
    lock = lock or load_lock()
    return list(lock["serve"])


def served_files(directory: str, lock: dict[str, Any] | None = None) -> dict[str, Path]:
    """Returns the files served at /static/vendor/<directory>/: URL path below it -> file (present or not)."""
    lock = lock or load_lock()
    return {url: FILES / rel for url, rel in lock["serve"][directory].items()}


def all_served_files(lock: dict[str, Any] | None = None) -> dict[str, Path]:
    """Returns every served file: URL path below /static/vendor/ -> file (present or not)."""
    lock = lock or load_lock()
    return {f"{d}/{url}": path for d in served_directories(lock) for url, path in served_files(d, lock).items()}


def model_info(model: str = "lite", lock: dict[str, Any] | None = None) -> ModelInfo:
    """Returns the pinned facts of the `.task` of `model` ("lite" or "full")."""
    if model not in MODELS:
        raise ValueError(f"model must be one of {', '.join(MODELS)}, got {model!r}")
    lock = lock or load_lock()
    task = next(t for t in lock["tasks"] if t["file"] == f"pose_landmarker_{model}.task")
    package = next(p for p in lock["npm"] if p["name"] == task["landmarks"]["package"])
    return ModelInfo(task["file"], task["model"], task["sha256"], f"{package['name']}@{package['version']}")


def task_path(model: str = "lite") -> Path:
    """Returns the installed `.task` of `model`; raises VendorError when it is not installed."""
    info = model_info(model)
    path = FILES / "models" / info.name
    if not path.is_file():
        raise VendorError(f"the pose model {info.name} is not installed: {INSTALL_HINT}")
    return path
