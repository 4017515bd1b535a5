"""From landmark batches to the 20-joint skeleton the pipeline takes: the one place the server calls the webcam
source's mapping (kinect_agent.sources.webcam.mapping) and its pipeline settings."""

from __future__ import annotations

import numpy as np

from kinect_agent.processing.config import PipelineConfig, config_for_device
from kinect_agent.recording import Metadata, Recording
from kinect_agent.sources.webcam import mapping
from kinect_agent.sources.webcam.landmarks import LandmarkBatch

WEBCAM = "webcam"  # the device name of sessions recorded with the browser's camera


def pipeline_config() -> PipelineConfig:
    """Returns the pipeline settings of the webcam (its noise model and filter settings)."""
    return config_for_device(WEBCAM)


def camera_frames(batch: LandmarkBatch) -> tuple[np.ndarray, np.ndarray]:
    """Returns (positions (N, 20, 3) m Kinect camera frame NaN = untracked, state (N, 20) 0/1/2) of a batch."""
    mapped = mapping.to_skeletons(batch)
    return mapped.positions, mapped.state


def to_recording(batches: list[LandmarkBatch], meta: Metadata) -> Recording:
    """Returns the batches' frames, one after the other, as a Recording (t on the set's clock, s); each batch is
    mapped with its own image size (a reload may bring another camera)."""
    mapped = [camera_frames(b) for b in batches]
    t = np.concatenate([b.t for b in batches])
    positions = np.concatenate([p for p, _ in mapped])
    state = np.concatenate([s for _, s in mapped])
    return Recording(t, positions, state, meta)
