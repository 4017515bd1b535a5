"""Which pipeline made a session file's filtered recording, and whether today's pipeline would make another one.

A session file's params (kinect_agent.formats.session_file.SessionPayload.params) record the pipeline that filtered
it: params["pipeline"] = pipeline.VERSION and params["config"] = every PipelineConfig value used. Today's pipeline
for a recording is (VERSION, config_for_device(its device)); a file made by anything else (another version, other
settings, no filtered recording, or a file of another tool with neither) is "stale", and the server's re-analysis
(`coach-server reanalyze --pipeline`) filters its raw recording again.
"""

from __future__ import annotations

import hashlib
import json
from typing import Any

from kinect_agent.processing.config import DEVICE_SETTINGS, PipelineConfig, config_for_device
from kinect_agent.processing.pipeline import VERSION, PipelineResult

QUALITY_KEYS = ("n_frames", "n_outliers", "n_gated", "frames_without_observation")


def pipeline_params(config: PipelineConfig, result: PipelineResult) -> dict[str, Any]:
    """Returns the params a session file records of its filtering: {"pipeline": VERSION, "config": every setting,
    "quality": {n_frames, n_outliers, n_gated, frames_without_observation}, "segment_lengths_m": {bone: m}}. No
    timings: the same recording must give the same bytes (the server deduplicates uploads on the hash)."""
    q = result.quality
    return {
        "pipeline": VERSION,
        "config": config.model_dump(),
        "quality": {k: q[k] for k in QUALITY_KEYS},
        "segment_lengths_m": q["segment_lengths_m"],
    }


def settings_id(config: dict[str, Any] | None) -> str | None:
    """Returns a short name of a params["config"] dict (12 hex digits of the sha256 of its sorted JSON), or None."""
    if not isinstance(config, dict):
        return None
    return hashlib.sha256(json.dumps(config, sort_keys=True).encode()).hexdigest()[:12]


def todays_id() -> str:
    """Returns a short name of today's pipeline for every device (VERSION, the defaults and DEVICE_SETTINGS): it
    changes whenever what stale_reason compares with changes, so a re-analysis job's key can carry it."""
    what = {"pipeline": VERSION, "defaults": PipelineConfig().model_dump(), "devices": DEVICE_SETTINGS}
    return hashlib.sha256(json.dumps(what, sort_keys=True).encode()).hexdigest()[:12]


def stale_reason(params: dict[str, Any], *, has_filtered: bool, device: str | None) -> str | None:
    """Returns why today's pipeline for `device` would filter the recording again, in words, or None when the file's
    filtered recording was made by it (same VERSION and the same settings, compared as JSON)."""
    if not has_filtered:
        return "the file has no filtered recording"
    made_by = params.get("pipeline")
    if made_by != VERSION:
        return (
            f"filtered by pipeline {made_by!r}, today's is {VERSION!r}"
            if made_by
            else "filtered by an unnamed pipeline"
        )
    today = json.loads(json.dumps(config_for_device(device).model_dump()))
    stored = params.get("config")
    if stored != today:
        changed = _changed_settings(stored, today)
        return f"filtered with other settings than today's for device {device or 'kinect_v2'!r}: {changed}"
    return None


def _changed_settings(stored: object, today: dict[str, Any]) -> str:
    """Returns the settings that differ, "name stored → today" (at most 5 named), or "none recorded"."""
    if not isinstance(stored, dict):
        return "none recorded"
    names = sorted(k for k in set(stored) | set(today) if stored.get(k, "absent") != today.get(k, "absent"))
    listed = ", ".join(f"{k} {stored.get(k, 'absent')!r} → {today.get(k, 'absent')!r}" for k in names[:5])
    return listed + (f" and {len(names) - 5} more" if len(names) > 5 else "")


__all__ = ["QUALITY_KEYS", "VERSION", "pipeline_params", "settings_id", "stale_reason", "todays_id"]
