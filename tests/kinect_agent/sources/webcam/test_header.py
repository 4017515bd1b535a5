"""The webcam session header: what both the agent and the server write, and what the pages and exports read."""

from __future__ import annotations

from kinect_agent.analysis.validity import recorded_with
from kinect_agent.sources.webcam.header import webcam_header
from kinect_agent.vendor import model_info


def test_the_header_names_the_pinned_model_and_reads_back_as_recorded_with() -> None:
    header = webcam_header(model="full", runtime="@mediapipe/tasks-vision 1.1.0 (browser)", fps_achieved=14.987,
                           image_size=(640, 480), images=300)  # fmt: skip
    assert header["model"] == model_info("full").to_dict() and header["fps_achieved"] == 14.99
    assert header["image_size"] == [640, 480] and header["fov_deg"] == 65.0
    seen = recorded_with("webcam", {"webcam": header})
    assert seen == {"device": "webcam", "label": "ordinary camera (webcam)", "model": "pose_landmarker_full.task",
                    "model_sha256": model_info("full").sha256, "runtime": "@mediapipe/tasks-vision 1.1.0 (browser)",
                    "fps_achieved": 14.99}  # fmt: skip


def test_a_header_of_the_wrong_shape_reads_as_unknown_not_as_an_error() -> None:
    for extra in (None, {}, {"webcam": "x"}, {"webcam": {"model": 3, "fps_achieved": True, "runtime": ["a"]}}):
        seen = recorded_with("webcam", extra)
        assert seen["model"] is None and seen["fps_achieved"] is None and seen["runtime"] is None, extra
