"""The camera set's live count against its saved count on the camera tests' clip (Sports2D's demo, BSD-3-Clause, the
fake camera's 640 x 360 .y4m of tests/fake_camera.py), through the Python runtime (MediaPipe, the pinned lite .task).

    nice -n 10 .venv/bin/python bench/webcam_live_clip.py [--rates 12 2] [--passes 1 3 6]

The fake camera plays the 30-fps clip in a loop; the page analyses the newest image at its own rate. Here: the image
shown at t = k / rate (k = 0, 1, ...; image int(30 t) mod 230), analysed in VIDEO mode, the patient chosen as the
agent's source chooses (choose_person), for `passes` passes of the clip; the landmarks are cached in
var/bench-cache/webcam/. Then the server's path: the batch mapped (backend.camera.skeleton.camera_frames), on the
session file's grid, the webcam's live filter and LiveCount frame by frame (the exercise of the camera browser tests:
squat): "shown" is the largest count the page was sent during the set, "final" the live count at the end (the result
screen's "while you exercised"), "stored" the saved session's (analyze_recording of the set's recording). The delay
of the shown count: for each stored repetition k, the time from its end (the whole set's analysis) to the first
frame whose shown count reached k.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from backend.camera.skeleton import camera_frames, to_recording  # noqa: E402
from kinect_agent.analysis.exercise import EXERCISES  # noqa: E402
from kinect_agent.analysis.live import LiveCount  # noqa: E402
from kinect_agent.analysis.report import analyze_recording  # noqa: E402
from kinect_agent.formats.session_file import on_grid  # noqa: E402
from kinect_agent.processing.config import config_for_device  # noqa: E402
from kinect_agent.processing.online import live_filter  # noqa: E402
from kinect_agent.recording import Metadata  # noqa: E402
from kinect_agent.sources.webcam.landmarks import LandmarkBatch  # noqa: E402

CACHE = REPO / "var" / "bench-cache" / "webcam"
CLIP_FPS = 30  # the .y4m's rate (tests/fake_camera.py write_y4m)
EXERCISE = "squat"  # the camera browser tests' exercise (tests/frontend/test_camera_set.py)


def clip_landmarks(rate: float, passes: int) -> LandmarkBatch:
    """Returns the patient's landmarks of `passes` passes of the looped clip analysed `rate` times a second."""
    path = CACHE / f"sports2d-live-{rate:g}fps-{passes}x.npz"
    if path.is_file():
        z = np.load(path)
        return LandmarkBatch(z["t"], z["world"], z["image"], z["visibility"], (640, 360))
    from kinect_agent.sources.webcam.source import choose_person, import_runtime, landmarker_options
    from kinect_agent.vendor import task_path
    from tests.fake_camera import read_y4m, sports2d_y4m, y4m_frame_count

    with tempfile.TemporaryDirectory() as tmp:
        clip = sports2d_y4m(Path(tmp) / "sports2d.y4m")
        n = y4m_frame_count(clip)
        images = read_y4m(clip, list(range(n)))
    _, mp, vision = import_runtime()
    times = np.arange(int(passes * n / CLIP_FPS * rate)) / rate
    rows: list[tuple[float, np.ndarray, np.ndarray, np.ndarray]] = []
    hips = None
    with vision.PoseLandmarker.create_from_options(landmarker_options(mp, vision, task_path("lite"))) as landmarker:
        for t in times:
            rgb = images[int(t * CLIP_FPS) % n]
            r = landmarker.detect_for_video(mp.Image(image_format=mp.ImageFormat.SRGB, data=rgb), int(round(t * 1000)))
            if not r.pose_landmarks:
                continue
            people = [np.array([[p.x, p.y, p.z] for p in person]) for person in r.pose_landmarks]
            k = choose_person(people, hips)
            hips = people[k][[23, 24], :2].mean(axis=0)
            world = np.array([[p.x, p.y, p.z] for p in r.pose_world_landmarks[k]])
            vis = np.clip([p.visibility or 0.0 for p in r.pose_landmarks[k]], 0.0, 1.0)
            rows.append((float(t), world, people[k], vis))
    batch = LandmarkBatch(np.array([r[0] for r in rows]), np.stack([r[1] for r in rows]),
                          np.stack([r[2] for r in rows]), np.stack([r[3] for r in rows]), (640, 360))  # fmt: skip
    CACHE.mkdir(parents=True, exist_ok=True)
    np.savez(path, t=batch.t, world=batch.world, image=batch.image, visibility=batch.visibility)
    return batch


@dataclass(frozen=True)
class ClipCounts:
    """One looped set's counts: the largest shown, the live count at the end, the saved one; the delay (s) of each
    saved repetition's display (None: shown only by the end's count)."""

    shown: int
    final: int
    stored: int
    delays: list[float | None]


def live_and_stored(batch: LandmarkBatch, exercise: str = EXERCISE) -> ClipCounts:
    """Returns the set's shown, final and stored counts and the delay (s) of each stored repetition's display."""
    spec = EXERCISES[exercise]
    positions, tracking = camera_frames(batch)
    positions = on_grid(positions)
    filt, counter = live_filter(config_for_device("webcam")), LiveCount(tuple(spec.defining_angles), device="webcam")
    shown = np.zeros(batch.n_frames, dtype=int)
    for k in range(batch.n_frames):
        t = float(batch.t[k])
        shown[k] = counter.add(t, positions[k], tracking[k], filt.step(t, positions[k], tracking[k])).count
    final = counter.final()
    meta = Metadata(device="webcam", rate_hz=float(1 / np.median(np.diff(batch.t))), exercise=exercise)
    report = analyze_recording(to_recording([batch], meta), spec)
    ends = [float(batch.t[0]) + r.end_s for r in report.repetition_list]
    delays: list[float | None] = []
    for i, end in enumerate(ends, start=1):
        reached = np.flatnonzero(shown >= i)
        delays.append(float(batch.t[reached[0]]) - end if reached.size else None)
    return ClipCounts(int(shown.max(initial=0)), final, report.repetitions, delays)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rates", type=float, nargs="+", default=[12.0, 2.0])
    parser.add_argument("--passes", type=int, nargs="+", default=[1, 3, 6])
    args = parser.parse_args()
    for rate in args.rates:
        for passes in args.passes:
            batch = clip_landmarks(rate, passes)
            out = live_and_stored(batch)
            delays = ", ".join("-" if d is None else f"{d:+.2f}" for d in out.delays)
            print(f"{rate:4g} fps, {passes} passes ({batch.n_frames} frames with the person): shown {out.shown}, "
                  f"final {out.final}, stored {out.stored}; delay s per stored repetition: {delays}",
                  flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
