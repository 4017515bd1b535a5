"""Capture sources of the home agent (devices, file replay, the calibrated simulator) and `record`.

Hardware sources import their SDK only when opened, so importing this package never needs one.
"""

from __future__ import annotations

from pathlib import Path

from kinect_agent.sources.base import Frame, Source, record

SOURCES = ("simulator", "replay", "kinect_v2", "azure_kinect", "webcam")
__all__ = ["SOURCES", "Frame", "Source", "make_source", "record"]


def make_source(
    name: str,
    *,
    file: str | Path | None = None,
    exercise: str | None = None,
    realtime: bool = True,
    seed: int = 0,
    device: str | None = None,
    camera: int | None = None,
    model: str | None = None,
) -> Source:
    """Returns the source called `name` (one of SOURCES), not yet opened; raises ValueError for bad settings.

    webcam: camera index `camera` (default 0), or the video `file` played instead; model "lite" (default) or "full".
    """
    if name != "webcam" and (camera is not None or model is not None):
        raise ValueError(f"--camera and --model are only for the webcam source, not {name}")
    if name == "webcam":
        from kinect_agent.sources.webcam.source import WebcamSource

        if file is not None and camera is not None:
            raise ValueError("give the webcam source a camera (--camera N) or a VIDEO file, not both")
        if camera is not None and not 0 <= camera <= 99:
            raise ValueError(f"--camera must be a camera index 0..99, got {camera}")
        if exercise is not None:
            raise ValueError("--exercise is only for the simulator source, not webcam")
        return WebcamSource(camera=camera or 0, video=file, model=model or "lite", realtime=realtime)
    if name == "replay":
        from kinect_agent.sources.replay import ReplaySource

        if file is None:
            raise ValueError("the replay source needs a file (--file F)")
        return ReplaySource(file, realtime=realtime)
    if file is not None:
        raise ValueError(f"--file is only for the replay source, not {name}")
    if name == "simulator":
        from kinect_agent.sources.simulator import SimulatorSource

        return SimulatorSource(exercise or "shoulder_abduction", device=device or "kinect2", seed=seed,
                               realtime=realtime)  # fmt: skip
    if exercise is not None:
        raise ValueError(f"--exercise is only for the simulator source, not {name}")
    if name == "kinect_v2":
        from kinect_agent.sources.kinect_v2 import KinectV2Source

        return KinectV2Source()
    if name == "azure_kinect":
        from kinect_agent.sources.azure_kinect import AzureKinectSource

        return AzureKinectSource(device=device or "azure_kinect")
    raise ValueError(f"unknown source {name!r}; known sources: {', '.join(SOURCES)}")
