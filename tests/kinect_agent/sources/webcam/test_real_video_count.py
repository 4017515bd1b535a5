"""A real person's repetitions counted from a real video, as the home agent counts them: the Musical Gestures
Toolbox's dancer (PyPI `musicalgestures` 1.32.0, GPL-3.0-or-later, University of Oslo fourMs Lab; tests/media.py),
filmed from the front, raises both arms out to the side four times in the clip's first 49.2 s and then stands still
(counted by eye, frame by frame: bench/README.md, "Counts on real videos of known counts"). The agent's webcam source
(`kinect-agent run --source webcam VIDEO`, MediaPipe's Python runtime, the pinned lite model and the full one) records
the set as a shoulder abduction; its live count (the online filter and LiveCount, as kinect_agent.live.set_recorder runs
them) and the saved session's count (the server's analysis of the stored raw recording) are both 4, with either model.

Before (the shoulder abduction counted on its frontal-plane angle, unmasked, wrapped at -120/240 degrees): the full
model's stored count was 2: the left arm comes down in front of the body after the first raise, its angle crossed the
seam (225 to -118 degrees) and the first three raises merged (bench/README.md, "The dancer's left shoulder across the
planar seam")."""

from __future__ import annotations

import pytest

from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.analysis.live import LiveCount
from kinect_agent.analysis.report import analyze_recording
from kinect_agent.formats.session_file import as_stored
from kinect_agent.processing.config import config_for_device
from kinect_agent.processing.online import live_filter
from kinect_agent.sources import record
from kinect_agent.sources.webcam.source import WebcamSource
from tests.media import mgt_dancer

pytest.importorskip("mediapipe")

SET_S = 49.2  # the four arm raises (frames 72-944 at 25 fps) and the stillness after them, before the solo that ends
TRUE_COUNT = 4  # counted by eye


@pytest.fixture(scope="module", params=["lite", "full"])
def dancer_set(request):
    """The dancer's first SET_S seconds through the agent's webcam source with the pose model `lite` or `full`, as a
    shoulder abduction set."""
    rec = record(WebcamSource(video=mgt_dancer(), realtime=False, model=request.param), SET_S)
    rec.meta.exercise = "shoulder_abduction"
    return rec


def test_the_agent_follows_the_dancer_through_the_whole_set(dancer_set) -> None:
    assert dancer_set.meta.device == "webcam"
    assert dancer_set.n_frames >= 0.95 * SET_S * 25  # the dancer is found in (nearly) every image
    assert dancer_set.duration == pytest.approx(SET_S, abs=0.1)


def test_four_arm_raises_are_counted_four_times_live_and_saved(dancer_set) -> None:
    spec = EXERCISES["shoulder_abduction"]
    online, counter = live_filter(config_for_device("webcam")), LiveCount(spec.defining_angles, device="webcam")
    for k in range(dancer_set.n_frames):
        t, positions, state = float(dancer_set.t[k]), dancer_set.positions[k], dancer_set.state[k]
        counter.add(t, positions, state, online.step(t, positions, state))
    assert counter.final() == TRUE_COUNT
    assert analyze_recording(as_stored(dancer_set), spec).repetitions == TRUE_COUNT
