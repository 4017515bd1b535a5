"""The pinned pose runtime and models and plotly.js are served from the app's own origin, exactly the files of the
lock."""

from __future__ import annotations

import hashlib

import pytest

from kinect_agent import vendor

# the pages chart with scatter, bar and heatmap traces: plotly.js's cartesian bundle (1.5 MB against the full 4.8 MB)
PLOTLY = "plotly.js-cartesian-dist-min"


@pytest.mark.parametrize(
    ("directory", "path", "media_type"),
    [
        ("mediapipe", "vision_bundle.mjs", "text/javascript; charset=utf-8"),
        ("mediapipe", "wasm/vision_wasm_internal.wasm", "application/wasm"),
        ("mediapipe", "wasm/vision_wasm_nosimd_internal.js", "text/javascript; charset=utf-8"),
        ("mediapipe", "pose_landmarker_lite.task", "application/octet-stream"),
        ("plotly", "plotly.min.js", "text/javascript; charset=utf-8"),
    ],
)
def test_a_served_asset_comes_with_its_media_type(client, directory, path, media_type) -> None:
    answer = client.get(f"/static/vendor/{directory}/{path}")
    assert answer.status_code == 200, answer.text[:200]
    assert answer.headers["content-type"] == media_type
    assert answer.content == vendor.served_files(directory)[path].read_bytes()


def test_the_served_plotly_is_the_pinned_npm_release(client) -> None:
    package = next(p for p in vendor.load_lock()["npm"] if p["name"] == PLOTLY)
    marker = (vendor.package_dir(PLOTLY) / ".integrity").read_text().strip()
    assert marker == package["integrity"]  # the unpacked copy is of the checked tarball
    head = client.get("/static/vendor/plotly/plotly.min.js").content[:200].decode()
    assert "plotly.js (cartesian - minified)" in head and f"v{package['version']}" in head, head


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


@pytest.mark.parametrize(
    "path", ["plotly/package.json", "plotly/plotly.js", "plotly/..%2F..%2Flock.json", "plotly.min.js",
             "mediapipe/plotly.min.js", "plotly.js-cartesian-dist-min/plotly-cartesian.min.js"],
)  # fmt: skip
def test_only_the_locked_plotly_file_is_served(client, path) -> None:
    assert client.get(f"/static/vendor/{path}").status_code == 404
