"""Which pipeline made a session file's filtered recording, and whether today's would make another one."""

from __future__ import annotations

import json
from typing import Any

from kinect_agent.processing.config import config_for_device
from kinect_agent.processing.pipeline import VERSION
from kinect_agent.processing.provenance import settings_id, stale_reason, todays_id


def _params(device: str | None) -> dict[str, Any]:
    return {"pipeline": VERSION, "config": json.loads(json.dumps(config_for_device(device).model_dump()))}


def test_a_file_of_todays_pipeline_for_its_device_is_current():
    assert stale_reason(_params(None), has_filtered=True, device="kinect_v2") is None
    assert stale_reason(_params("webcam"), has_filtered=True, device="webcam") is None


def test_a_raw_only_file_is_stale():
    assert stale_reason(_params(None), has_filtered=False, device=None) == "the file has no filtered recording"


def test_another_pipeline_version_is_stale():
    params = _params(None) | {"pipeline": "ukf-4pass v0"}
    assert stale_reason(params, has_filtered=True, device=None) == (
        f"filtered by pipeline 'ukf-4pass v0', today's is {VERSION!r}"
    )


def test_the_kinect_settings_on_a_webcam_recording_are_stale_and_named():
    reason = stale_reason(_params(None), has_filtered=True, device="webcam")
    assert reason is not None and "offline_filter 'chain' → 'joints'" in reason, reason
    assert "remove_outliers True → False" in reason, reason


def test_settings_without_a_new_field_are_stale():
    params = _params(None)
    del params["config"]["joint_accel_sd_mps2"]
    reason = stale_reason(params, has_filtered=True, device=None)
    assert reason is not None and "joint_accel_sd_mps2 'absent' → 50.0" in reason, reason


def test_short_names_are_stable_and_tell_settings_apart():
    assert settings_id(_params(None)["config"]) == settings_id(dict(reversed(_params(None)["config"].items())))
    assert settings_id(_params(None)["config"]) != settings_id(_params("webcam")["config"])
    assert settings_id(None) is None and len(todays_id()) == 12
