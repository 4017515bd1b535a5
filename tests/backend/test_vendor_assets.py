"""The pinned pose runtime and models are served from the app's own origin, exactly the files of the lock."""

from __future__ import annotations

import hashlib

import pytest

from kinect_agent import vendor


@pytest.mark.parametrize(
    ("path", "media_type"),
    [
        ("vision_bundle.mjs", "text/javascript; charset=utf-8"),
        ("wasm/vision_wasm_internal.wasm", "application/wasm"),
        ("wasm/vision_wasm_nosimd_internal.js", "text/javascript; charset=utf-8"),
        ("pose_landmarker_lite.task", "application/octet-stream"),
    ],
)
def test_a_served_asset_comes_with_its_media_type(client, path, media_type) -> None:
    answer = client.get(f"/static/vendor/mediapipe/{path}")
    assert answer.status_code == 200, answer.text[:200]
    assert answer.headers["content-type"] == media_type
    assert answer.content == vendor.served_files()[path].read_bytes()


def test_the_served_model_is_the_pinned_one(client) -> None:
    answer = client.get("/static/vendor/mediapipe/pose_landmarker_full.task")
    assert hashlib.sha256(answer.content).hexdigest() == vendor.model_info("full").sha256


@pytest.mark.parametrize(
    "path",
    ["package.json", "pose_landmark_heavy.tflite", "../lock.json", "..%2Flock.json", "npm/@mediapipe/pose/package.json",
     "wasm/", ""],
)  # fmt: skip
def test_anything_not_in_the_lock_is_not_found(client, path) -> None:
    assert client.get(f"/static/vendor/mediapipe/{path}").status_code == 404
