"""From landmark batches to the 20-joint skeleton the pipeline takes: the one place the server calls the webcam
source's mapping (kinect_agent.sources.webcam) and its per-device pipeline settings."""

from __future__ import annotations

import numpy as np

from backend.camera.batch import LandmarkBatch
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.recording import Metadata, Recording

WEBCAM = "webcam"  # the device name of sessions recorded with the browser's camera


def pipeline_config() -> PipelineConfig:
    """Returns the pipeline settings of the webcam (its noise model and filter settings)."""
    from kinect_agent.processing.config import config_for_device

    return config_for_device(WEBCAM)


def camera_frames(batch: LandmarkBatch) -> tuple[np.ndarray, np.ndarray]:
    """Returns (positions (T, 20, 3) m camera frame NaN = untracked, state (T, 20) 0/1/2) of the batch's frames."""
    from kinect_agent.sources.webcam import mapping

    return mapping.to_skeleton(batch.world, batch.image, batch.visibility)


def to_recording(batch: LandmarkBatch, meta: Metadata) -> Recording:
    """Returns the batch's frames as a Recording (t from the set's clock, s) with the given metadata."""
    positions, state = camera_frames(batch)
    return Recording(batch.t.astype(np.float64), positions, state, meta)
