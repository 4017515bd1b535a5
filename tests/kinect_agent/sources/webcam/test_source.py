"""The agent's webcam source on real video (Sports2D's and Pose2Sim's demos, BSD-3-Clause, see tests/media.py)."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.errors import DeviceUnavailable
from kinect_agent.sources import record
from kinect_agent.sources.webcam.source import WebcamSource, choose_person
from kinect_agent.vendor import model_info
from tests.media import pose2sim_view, sports2d_demo

pytest.importorskip("mediapipe")
IDX = skeleton.INDEX


@pytest.fixture(scope="module")
def sports2d_take():
    """The first 2 s of Sports2D's demo through the source: (recording, source)."""
    source = WebcamSource(video=sports2d_demo(), realtime=False)
    return record(source, 2.0), source


def test_a_side_view_gives_an_upright_person_with_human_proportions(sports2d_take) -> None:
    rec, _ = sports2d_take
    assert rec.n_frames >= 50, rec.n_frames  # 61 images; the person is found within the first few
    assert np.all(np.diff(rec.t) > 0) and abs(np.median(np.diff(rec.t)) - 1 / 30) < 1e-9
    p = np.nanmedian(rec.positions, axis=0)  # (20, 3) m, Kinect camera frame
    assert p[IDX["HEAD"], 1] > p[IDX["NECK"], 1] > p[IDX["ROOT"], 1] > p[IDX["KNE_L"], 1] > p[IDX["ANK_L"], 1]  # y up
    assert 2.0 < p[IDX["ROOT"], 2] < 15.0  # in front of the camera
    lengths = dict(zip(skeleton.SEGMENT_NAMES, np.nanmedian(rec.segment_lengths(), axis=0), strict=True))
    for name, (low, high) in {"LEG_UP_L": (0.3, 0.5), "LEG_LO_R": (0.3, 0.5), "ARM_UP_R": (0.2, 0.35)}.items():
        assert low < lengths[name] < high, (name, lengths[name])
    tracked = (rec.state == skeleton.TRACKED).mean(axis=0)
    assert tracked[IDX["ROOT"]] > 0.9 and tracked[IDX["HEAD"]] > 0.9


def test_the_session_header_names_the_device_the_model_and_the_rates(sports2d_take) -> None:
    rec, source = sports2d_take
    assert rec.meta.device == "webcam" and rec.meta.rate_hz == pytest.approx(30.0)
    webcam = rec.meta.extra["webcam"]
    assert webcam["model"] == model_info("lite").to_dict()
    assert webcam["runtime"].startswith("mediapipe 1.2.3") and webcam["image_size"] == [1768, 994]
    assert webcam["fps_achieved"] > 0.5 and webcam["images"] >= rec.n_frames
    batch = source.landmark_batch()
    assert batch.image_size == (1768, 994)  # record() reads one frame past its end: the batch may hold one more
    np.testing.assert_allclose(batch.t[: rec.n_frames] - batch.t[0], rec.t, atol=1e-12)


@pytest.mark.parametrize("watch", [True, False])
def test_the_patient_is_kept_when_a_second_person_is_in_view(watch: bool) -> None:
    """With the company watch (shipped) and with one landmarker looking for two on every image (watch=False, the
    benchmarks' "before")."""
    # Pose2Sim's cam01: the subject walks in front; a second person stands at the back on the left
    source = WebcamSource(video=pose2sim_view(1), realtime=False, watch=watch)
    source.open()
    assert (source.company_watch is not None) == watch
    source.close()
    rec = record(source, 0.5)
    hips = np.array([f.image[[23, 24], :2].mean(axis=0) for f in source.landmark_frames])
    assert rec.n_frames >= 25
    assert np.max(np.abs(np.diff(hips, axis=0))) < 0.05, "no jump to the other person"
    assert 0.3 < hips[:, 0].mean() < 0.8  # the subject, not the person at the image's left edge


def test_choose_person_follows_the_nearest_hips_and_starts_with_the_largest() -> None:
    small = np.zeros((33, 3)) + [0.1, 0.1, 0.0]
    small[:, :2] += np.linspace(0, 0.05, 33)[:, None]
    large = np.zeros((33, 3)) + [0.5, 0.3, 0.0]
    large[:, :2] += np.linspace(0, 0.5, 33)[:, None]
    assert choose_person([small, large], None) == 1
    assert choose_person([small, large], small[[23, 24], :2].mean(axis=0)) == 0


def test_a_missing_video_or_camera_is_one_clear_line(tmp_path) -> None:
    with pytest.raises(DeviceUnavailable, match="does not exist"):
        WebcamSource(video=tmp_path / "none.mp4").open()
    (tmp_path / "bad.mp4").write_bytes(b"not a video")
    with pytest.raises(DeviceUnavailable, match="cannot be opened"):
        WebcamSource(video=tmp_path / "bad.mp4").open()
    with pytest.raises(DeviceUnavailable, match="camera 99 cannot be opened"):
        WebcamSource(camera=99).open()
