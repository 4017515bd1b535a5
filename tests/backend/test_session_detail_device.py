"""The session detail says which device recorded the session and which of its metrics that device supports."""

from __future__ import annotations

import uuid
from typing import Any

import numpy as np

from kinect_agent.formats import session_file as sf
from kinect_agent.recording import Recording
from kinect_agent.sources.simulator import simulate
from kinect_agent.vendor import model_info

WEBCAM_HEADER = {"webcam": {"model": model_info("lite").to_dict(), "runtime": "mediapipe 1.2.3 (Python)",
                            "fps_achieved": 14.5, "fov_deg": 65.0}}  # fmt: skip


def _side_on(rec: Recording) -> Recording:
    """The recording turned 90 degrees about the vertical through its mean root: seen from the side."""
    centre = np.nanmean(rec.positions[:, 0], axis=0)
    R = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    return rec.replace(positions=(rec.positions - centre) @ R.T + centre)


def _khs(device: str, *, side: bool, seed: int = 3) -> bytes:
    measured, truth, _ = simulate("squat", 3, seed=seed)
    raw, filtered = (_side_on(measured), _side_on(truth)) if side else (measured, truth)
    raw.meta.device = filtered.meta.device = device
    if device == "webcam":
        raw.meta.extra.update(WEBCAM_HEADER)
    payload = sf.SessionPayload(session_id=str(uuid.uuid4()), raw=raw, filtered=filtered,
                                created_at="2026-11-20T10:00:00Z")  # fmt: skip
    return sf.encode(payload)


def _detail(client, upload, auth_headers, data: bytes) -> dict[str, Any]:
    session_id, _, therapist = upload(data, "squat")
    response = client.get(f"/api/v1/sessions/{session_id}/detail", headers=auth_headers(therapist))
    assert response.status_code == 200, response.text
    return response.json()


def test_a_webcam_session_names_its_model_and_flags_what_one_camera_cannot_measure(client, upload, auth_headers):
    body = _detail(client, upload, auth_headers, _khs("webcam", side=True))
    assert body["recorded_with"] == {"device": "webcam", "label": "ordinary camera (webcam)",
                                     "model": "pose_landmarker_lite.task", "model_sha256": model_info("lite").sha256,
                                     "runtime": "mediapipe 1.2.3 (Python)", "fps_achieved": 14.5}  # fmt: skip
    validity = body["validity"]
    assert validity["device"] == "webcam" and validity["view"] == "side" and validity["limited"]
    metrics = {m["name"]: m for m in validity["metrics"]}
    assert metrics["knee_flexion_R"]["valid"] and metrics["rom"]["valid"] and metrics["repetitions"]["valid"]
    assert not metrics["joint_paths"]["valid"] and "assumed camera" in metrics["joint_paths"]["reason"]


def test_a_webcam_squat_filmed_from_the_front_flags_its_range_of_motion(client, upload, auth_headers):
    body = _detail(client, upload, auth_headers, _khs("webcam", side=False))
    metrics = {m["name"]: m for m in body["validity"]["metrics"]}
    assert body["validity"]["view"] == "front"
    assert not metrics["rom"]["valid"] and metrics["rom"]["code"] == "out_of_plane"
    assert "from the side" in metrics["rom"]["reason"]


def test_a_kinect_session_supports_every_metric(client, upload, auth_headers):
    body = _detail(client, upload, auth_headers, _khs("kinect2", side=False))
    assert body["recorded_with"]["label"] == "Kinect v2" and body["recorded_with"]["model"] is None
    assert not body["validity"]["limited"] and all(m["valid"] for m in body["validity"]["metrics"])
