"""A camera set's live count and its saved count are one count: the count the page shows last (the server's live
path: the webcam's live filter, causal, and LiveCount with the webcam's rules) equals the stored session's
repetitions (the analysis of the session file), on webcam-like sets with jitter and left/right swaps, with and
without repetitions, shallow ones too (kinect_agent.analysis.live.counting_positions, counting_params, amplitude_floor).

Before (the live count on the chain's online filter, the stored one on the joints smoother's RTS output): on the
camera tests' clip (Sports2D's demo, looped by Chromium's fake camera) the page counted 1 and then said "Saved: all
10 repetitions" (bench/README.md, "Webcam counts: the live count and the saved count, one count").
"""

from __future__ import annotations

import uuid
from typing import Any

import numpy as np
import pytest

from backend.camera import live_count
from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.analysis.live import LiveCount
from kinect_agent.analysis.report import analyze_recording
from kinect_agent.formats.session_file import on_grid
from kinect_agent.processing.config import config_for_device
from kinect_agent.processing.online import live_filter
from kinect_agent.processing.pipeline import process
from kinect_agent.sources.simulator import simulate_truth
from tests.backend.camera.landmarks import batch, frame, squats
from tests.webcam_like import webcam_like

PER_BATCH = 6
# BlazePose's 33 landmarks with left and right exchanged (nose 0 stays)
BLAZE_MIRROR = [0, 4, 5, 6, 1, 2, 3, 8, 7, 10, 9] + [i + 1 if i % 2 else i - 1 for i in range(11, 33)]


def webcam_frames(frames: list[dict[str, Any]], seed: int, swaps: bool) -> list[dict[str, Any]]:
    """Returns page frames with the webcam's measured jitter (10 mm across the image, 25 mm in depth) and, with swaps,
    a sixth of the set whose left and right labels flicker (the side view's swaps; bench/README.md, "Webcam")."""
    rng = np.random.default_rng(seed)
    out = []
    n = len(frames)
    for k, f in enumerate(frames):
        world = np.asarray(f["world"]) + rng.normal(0.0, 1.0, (33, 3)) * [0.01, 0.01, 0.025]
        image = np.asarray(f["image"]) + rng.normal(0.0, 0.003, (33, 3))
        if swaps and n // 3 <= k < n // 3 + n // 6 and rng.random() < 0.5:
            world, image = world[BLAZE_MIRROR], image[BLAZE_MIRROR]
        out.append(f | {"world": world.round(5).tolist(), "image": image.round(5).tolist()})
    return out


def _wobble(seconds: float, seed: int) -> list[dict[str, Any]]:
    """Frames of a person standing whose knees wobble by up to 12 degrees (no repetition), as page frames."""
    rng = np.random.default_rng(seed)
    n = int(seconds * 30)
    knee = np.abs(np.convolve(rng.normal(0.0, 12.0, n + 30), np.ones(30) / np.sqrt(30), mode="same")[15 : 15 + n])
    return [frame(k / 30, float(min(v, 12.0))) for k, v in enumerate(knee)]


@pytest.mark.parametrize(
    ("reps", "swaps", "seed", "depth_deg"),
    [(3, False, 0, 90.0), (3, True, 1, 90.0), (2, True, 2, 90.0), (0, True, 3, 0.0), (4, False, 4, 16.0)],
    ids=["3-squats", "3-squats-swaps", "2-squats-swaps", "standing-wobble-swaps", "4-mini-squats-16-degrees"],
)
def test_the_saved_count_is_the_last_live_count(client, db_session, camera_home, started, reps, swaps, seed, depth_deg):
    """The mini squats counted 0 live and 0 saved with the webcam's former fixed floor of 20 degrees."""
    set_id, h = started(seconds_ago=120), camera_home["headers"]
    frames = webcam_frames(squats(reps, depth_deg=depth_deg) if reps else _wobble(12.0, seed), seed, swaps)
    answers = []
    for seq, k in enumerate(range(0, len(frames), PER_BATCH)):
        r = client.post(f"/api/v1/camera/sets/{set_id}/batches", json=batch(seq, frames[k : k + PER_BATCH]),
                        headers=h)  # fmt: skip
        assert r.status_code == 201, r.text
        answers.append(r.json()["count"])
    final = live_count.final_count(uuid.UUID(set_id))
    r = client.post(f"/api/v1/camera/sets/{set_id}/end", json={"last_seq": len(answers) - 1, "reason": "stop"},
                    headers=h)  # fmt: skip
    assert r.status_code == 200 and r.json()["status"] == "stored", r.text
    stored = client.get(f"/api/v1/sessions/{r.json()['session_id']}", headers=h).json()["repetitions"]
    assert answers[-1] == final == stored == reps, f"live {answers}, final {final}, stored {stored}, true {reps}"


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("exercise", ["squat", "shoulder_abduction", "side_step"])
def test_the_live_path_and_the_stored_analysis_count_alike(exercise, seed):
    raw = webcam_like(simulate_truth(exercise, 4, seed=seed), seed)
    raw = raw.replace(positions=on_grid(raw.positions))  # as a stored session file holds them
    spec = EXERCISES[exercise]
    config = config_for_device("webcam")
    filt, counter = live_filter(config), LiveCount(tuple(spec.defining_angles), device="webcam")
    for k in range(raw.n_frames):
        t = float(raw.t[k])
        counter.add(t, raw.positions[k], raw.state[k], filt.step(t, raw.positions[k], raw.state[k]))
    live = counter.final()
    stored = analyze_recording(raw, spec, filtered=process(raw, config=config).filtered).repetitions
    assert live == stored, f"{exercise} seed {seed}: live {live}, stored {stored}"
