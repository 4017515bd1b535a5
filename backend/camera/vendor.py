"""Which landmarker model a set ran: its name, version and SHA-256, from the pinned assets the app serves."""

from __future__ import annotations

import functools
import hashlib


@functools.cache
def model_info(name: str) -> dict[str, str | None]:
    """Returns {"name", "version", "sha256"} of the pinned model `name` (a key of limits.MODELS); sha256 is None
    when the assets are not installed (python -m kinect_agent.vendor.install)."""
    from kinect_agent.vendor import install

    path = install.asset_path(f"{name}.task")
    sha = hashlib.sha256(path.read_bytes()).hexdigest() if path.is_file() else None
    return {"name": name, "version": install.MODEL_VERSION, "sha256": sha}
