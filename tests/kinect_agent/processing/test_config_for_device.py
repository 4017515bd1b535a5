"""Pipeline settings per recording device: the webcam's measured noise, Kinect's defaults for everything else."""

from __future__ import annotations

import pytest

from kinect_agent.capture import make_payload
from kinect_agent.processing.config import DEVICE_SETTINGS, PipelineConfig, config_for_device
from kinect_agent.recording import DEVICES
from kinect_agent.sources.simulator import simulate


@pytest.mark.parametrize("device", ["kinect1", "kinect2", "azure_kinect", "femto", "unknown", None, "no-such"])
def test_depth_cameras_and_unknown_devices_get_the_defaults(device) -> None:
    assert config_for_device(device) == PipelineConfig()


def test_the_webcam_trusts_each_sample_less_than_a_kinect() -> None:
    webcam, kinect = config_for_device("webcam"), PipelineConfig()
    assert webcam.sigma_tracked_m > kinect.sigma_tracked_m and webcam.sigma_inferred_m > kinect.sigma_inferred_m
    assert webcam.online_sigma_tracked_m > kinect.online_sigma_tracked_m
    changed = {k for k in PipelineConfig.model_fields if getattr(webcam, k) != getattr(kinect, k)}
    assert changed == set(DEVICE_SETTINGS["webcam"])


def test_every_device_setting_names_a_device_and_valid_fields() -> None:
    for device, settings in DEVICE_SETTINGS.items():
        assert device in DEVICES
        PipelineConfig(**settings)  # refuses unknown fields and out-of-range values


def test_the_agent_filters_a_webcam_recording_with_the_webcam_settings() -> None:
    measured = simulate("squat", 2, seed=4)[0]
    measured.meta.device = "webcam"
    payload = make_payload(measured, created_at="2026-11-20T10:00:00Z")
    assert payload.params["config"]["sigma_tracked_m"] == DEVICE_SETTINGS["webcam"]["sigma_tracked_m"]
    measured.meta.device = "kinect2"
    payload = make_payload(measured, created_at="2026-11-20T10:00:00Z")
    assert payload.params["config"]["sigma_tracked_m"] == PipelineConfig().sigma_tracked_m
