"""Landmarks of the public demo clips used by the webcam benchmarks, computed once and cached.

Clips (fetched and hash-checked by tests/media.py; BSD-3-Clause, perfanalytics): Sports2D's demo (one person, side
view, 30 fps) and the four calibrated views of Pose2Sim's single-person demo (60 fps); GPL-3.0-or-later, University
of Oslo: the Musical Gestures Toolbox's dancer (front view, 25 fps, bench/webcam_counts.py --cases videos). Each
clip is run through the agent's WebcamSource (MediaPipe's Python runtime, the pinned lite or full .task) and its
LandmarkBatch kept in var/bench-cache/webcam/<clip>-<model>.npz, so the benchmarks after the first run cost seconds.
landmarker "two": the source before its company watch (one landmarker looking for two people on every image, as
until 2026-11-28), cached as <clip>-<model>-two.npz. The runtime gives the same landmarks on every run (checked on
the Pose2Sim views, 2026-11-28), so one run is the median of any number.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from kinect_agent.sources.webcam.landmarks import LandmarkBatch  # noqa: E402
from tests.media import mgt_dancer, pose2sim_multi_view, pose2sim_view, sports2d_demo  # noqa: E402

CACHE = REPO / "var" / "bench-cache" / "webcam"
CLIPS: dict[str, Callable[[], Path]] = {
    "sports2d": sports2d_demo,
    **{f"pose2sim_cam{c}": partial(pose2sim_view, c) for c in (1, 2, 3, 4)},
    **{f"pose2sim_multi_cam{c}": partial(pose2sim_multi_view, c) for c in (1, 2, 3, 4)},
    "mgt_dancer": mgt_dancer,
}
RATES = {"sports2d": 30.0, **{f"pose2sim{m}_cam{c}": 60.0 for m in ("", "_multi") for c in (1, 2, 3, 4)}}
RATES["mgt_dancer"] = 25.0


def landmarks(clip: str, model: str = "lite", landmarker: str = "watch") -> tuple[LandmarkBatch, float]:
    """Returns (the clip's landmark batch, images analysed per second when it was computed); landmarker "watch" (the
    agent's source as shipped) or "two" (module docstring)."""
    if landmarker not in ("watch", "two"):
        raise ValueError(f"landmarker must be 'watch' or 'two', got {landmarker!r}")
    path = CACHE / f"{clip}-{model}{'' if landmarker == 'watch' else '-two'}.npz"
    if path.is_file():
        z = np.load(path)
        width, height = (int(v) for v in z["size"])
        batch = LandmarkBatch(z["t"], z["world"], z["image"], z["visibility"], (width, height))
        return batch, float(z["fps"])
    from kinect_agent.sources.webcam.source import WebcamSource

    source = WebcamSource(video=CLIPS[clip](), model=model, realtime=False, watch=landmarker == "watch")
    source.open()
    try:
        began = time.perf_counter()
        for _ in source.frames():
            pass
        fps = source.images / (time.perf_counter() - began)
    finally:
        source.close()
    batch = source.landmark_batch()
    CACHE.mkdir(parents=True, exist_ok=True)
    np.savez(path, t=batch.t, world=batch.world, image=batch.image, visibility=batch.visibility,
             size=np.array(batch.image_size), fps=fps)  # fmt: skip
    return batch, fps


if __name__ == "__main__":
    for name in CLIPS:
        for model in ("lite", "full"):
            b, f = landmarks(name, model)
            print(f"{name:16s} {model}: {b.n_frames} frames with the person, {f:.1f} images/s", flush=True)
