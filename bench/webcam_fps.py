"""Frames per second of the pose landmarker in MediaPipe's Python runtime (the agent's webcam source), lite and full.

    .venv/bin/python bench/webcam_fps.py [--frames 90] [--runs 3] [--size 640x360] [--people 1 2 watch] [--agent]

Frames: Sports2D's demo (tests/media.py, BSD-3-Clause) scaled to --size, decoded once beforehand (the decoding is
not timed); each run creates the landmarker (VIDEO mode, XNNPACK on the CPU) and times detect_for_video over the
frames. Prints the median of the runs and the per-frame p95, for the lite and full models and each number of
people searched, and for the agent's company watch ("watch": kinect_agent.sources.webcam.company, one person tracked
and a look for a second one once a second, as the agent and the browser page run it). The runs of the schemes
alternate, so each sees the same machine load.

--agent: the agent's webcam source instead of the bare landmarker (kinect_agent.sources.webcam.source.WebcamSource,
as `kinect-agent run --source webcam` runs it: decoding, colour conversion, the landmarker, the mapping to the 20
joints), on the same frames written to a video file (30 fps, as fast as it can: realtime off), with the company
watch ("watch") and with one landmarker looking for two people on every image ("2", the source before 2026-11-28);
the number is the source's fps_achieved, which the session's header records.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from kinect_agent.vendor import task_path  # noqa: E402
from tests.media import sports2d_demo  # noqa: E402


def frames(size: tuple[int, int], n: int) -> list[np.ndarray]:
    """Returns n RGB frames of the demo from 1 s on, scaled to size (width, height)."""
    import cv2

    cap = cv2.VideoCapture(str(sports2d_demo()))
    cap.set(cv2.CAP_PROP_POS_FRAMES, 30)
    out: list[np.ndarray] = []
    while len(out) < n:
        ok, bgr = cap.read()
        if not ok:
            cap.set(cv2.CAP_PROP_POS_FRAMES, 30)
            continue
        out.append(cv2.cvtColor(cv2.resize(bgr, size, interpolation=cv2.INTER_AREA), cv2.COLOR_BGR2RGB))
    return out


def run(model: str, people: str, images: list[np.ndarray]) -> tuple[float, float]:
    """Returns (images per second, p95 ms per image) of one pass over the images; people: "1", "2" or "watch"."""
    import mediapipe as mp
    from mediapipe.tasks.python import vision

    from kinect_agent.sources.webcam.company import TWO_DETECTION_CONFIDENCE, CompanyWatch
    from kinect_agent.sources.webcam.source import landmarker_options

    path = task_path(model)
    if people == "watch":
        made = [vision.PoseLandmarker.create_from_options(landmarker_options(mp, vision, path, people=1)),
                vision.PoseLandmarker.create_from_options(landmarker_options(
                    mp, vision, path, people=2, detection=TWO_DETECTION_CONFIDENCE))]  # fmt: skip
        landmarker: Any = CompanyWatch(*made)
    else:
        made = [vision.PoseLandmarker.create_from_options(landmarker_options(mp, vision, path, people=int(people)))]
        landmarker = made[0]
    try:
        times = []
        for i, rgb in enumerate(images):
            image = mp.Image(image_format=mp.ImageFormat.SRGB, data=rgb)
            began = time.perf_counter()
            landmarker.detect_for_video(image, i * 33)
            times.append(time.perf_counter() - began)
    finally:
        for m in made:
            m.close()
    return len(times) / sum(times), float(np.percentile(times, 95) * 1000)


def agent_run(model: str, people: str, video: Path) -> tuple[float, float, float]:
    """Returns (images per second as the source's header records it, CPU ms per image (every thread of the
    process: what a loaded machine does not change much), the share of images `one` answered) of WebcamSource over
    the video; people: "watch" or "2"."""
    from kinect_agent.sources.webcam.source import WebcamSource

    source = WebcamSource(video=video, model=model, realtime=False, watch=people == "watch")
    source.open()
    try:
        cpu = time.process_time()
        for _ in source.frames():
            pass
        cpu_ms = (time.process_time() - cpu) * 1000.0 / max(source.images, 1)
        watch = source.company_watch
        one = watch.runs["one"] / source.images if watch is not None and source.images else 0.0
    finally:
        source.close()
    return source.fps_achieved or float("nan"), cpu_ms, one


def write_video(images: list[np.ndarray], path: Path, fps: float = 30.0) -> Path:
    """Writes RGB images as an mp4 (mp4v) at fps; returns path."""
    import cv2

    height, width = images[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), fps, (width, height))
    for rgb in images:
        writer.write(cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    writer.release()
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=90)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--size", default="640x360")
    parser.add_argument("--people", nargs="+", default=["1", "2", "watch"], choices=["1", "2", "watch"])
    parser.add_argument("--agent", action="store_true", help="the agent's webcam source (watch and 2) on a video")
    args = parser.parse_args()
    width, height = (int(v) for v in args.size.split("x"))
    images = frames((width, height), args.frames)
    if args.agent:
        with tempfile.TemporaryDirectory() as tmp:
            video = write_video(images, Path(tmp) / "frames.mp4")
            print(
                f"the agent's webcam source, {args.frames} frames of {args.size} (a video), median of {args.runs} runs"
            )
            for model in ("lite", "full"):
                got: dict[str, list[tuple[float, float, float]]] = {"watch": [], "2": []}
                for _ in range(args.runs):
                    for people in got:
                        got[people].append(agent_run(model, people, video))
                for people, rows in got.items():
                    what = "company watch" if people == "watch" else "num_poses=2"
                    print(f"  {model:4s} {what:13s}: {statistics.median(r[0] for r in rows):5.1f} images/s (runs "
                          f"{', '.join(f'{r[0]:.1f}' for r in rows)}), CPU {statistics.median(r[1] for r in rows):.0f} "
                          f"ms per image, `one` answered {rows[0][2]:.0%} of images",
                          flush=True)  # fmt: skip
        return
    print(f"MediaPipe Python runtime, {args.frames} frames of {args.size}, median of {args.runs} runs")
    for model in ("lite", "full"):
        results: dict[str, list[tuple[float, float]]] = {p: [] for p in args.people}
        for _ in range(args.runs):
            for people in args.people:
                results[people].append(run(model, people, images))
        for people, res in results.items():
            fps = statistics.median(r[0] for r in res)
            p95 = statistics.median(r[1] for r in res)
            what = "company watch" if people == "watch" else f"num_poses={people}"
            print(f"  {model:4s} {what:13s}: {fps:5.1f} images/s (runs {', '.join(f'{r[0]:.1f}' for r in res)}), "
                  f"p95 {p95:5.1f} ms per image", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
