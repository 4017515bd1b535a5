"""Which landmarker model a set ran: its file name, what it is, its pinned SHA-256 and source (kinect_agent.vendor's
lock, checked when the assets are installed)."""

from __future__ import annotations

import functools


@functools.cache
def model_info(name: str) -> dict[str, str]:
    """Returns {"name", "model", "sha256", "source"} of the pinned model `name` (one of limits.MODELS)."""
    from kinect_agent.vendor import model_info as pinned

    return pinned(name.removeprefix("pose_landmarker_")).to_dict()
