"""The session header of a webcam recording (Metadata.extra["webcam"]), made the same way by the agent's source and by
the server for sets the browser page records, and read by kinect_agent.analysis.validity.recorded_with."""

from __future__ import annotations

from typing import Any

from kinect_agent.sources.webcam.mapping import DEFAULT_FOV_DEG
from kinect_agent.vendor import model_info


def webcam_header(
    *,
    model: str = "lite",
    runtime: str,
    fps_achieved: float | None,
    image_size: tuple[int, int] | None,
    fov_deg: float = DEFAULT_FOV_DEG,
    images: int | None = None,
) -> dict[str, Any]:
    """Returns Metadata.extra["webcam"]: {"model": {name, model, sha256, source} of the pinned .task, "runtime"
    (e.g. "mediapipe 1.2.3 (Python)" or "@mediapipe/tasks-vision 1.1.0 (browser)"), "fov_deg" assumed, "image_size"
    [width, height] px, "fps_achieved" images analysed per second, "images" analysed (None: unknown)}."""
    return {
        "model": model_info(model).to_dict(),
        "runtime": runtime,
        "fov_deg": fov_deg,
        "image_size": list(image_size) if image_size else None,
        "fps_achieved": round(float(fps_achieved), 2) if fps_achieved else None,
        "images": images,
    }
