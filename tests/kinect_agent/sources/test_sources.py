"""Capture sources: replay, the simulator as a live source, and the hardware adapters without their SDKs."""

from __future__ import annotations

import time

import numpy as np
import pytest

from kinect_agent import formats
from kinect_agent.errors import DeviceUnavailable
from kinect_agent.sources import make_source, record
from kinect_agent.sources.azure_kinect import AzureKinectSource
from kinect_agent.sources.kinect_v2 import KinectV2Source
from kinect_agent.sources.replay import ReplaySource
from kinect_agent.sources.simulator import SimulatorSource, simulate


@pytest.fixture
def session_csv(tmp_path):
    measured, _, _ = simulate("elbow_flexion", 2, seed=1)
    path = tmp_path / "session.csv"
    formats.write(measured, path)
    return path, formats.read(path)


def test_replay_as_fast_as_possible_gives_the_file_back(session_csv):
    path, original = session_csv
    rec = record(ReplaySource(path, realtime=False), seconds=1e6)
    np.testing.assert_allclose(rec.t, original.t - original.t[0])
    np.testing.assert_array_equal(rec.state, original.state)
    np.testing.assert_allclose(rec.positions, original.positions, equal_nan=True)
    assert rec.meta.device == "kinect2"


def test_replay_in_real_time_takes_the_recorded_time(session_csv):
    path, _ = session_csv
    start = time.monotonic()
    rec = record(ReplaySource(path, realtime=True), seconds=0.5)
    elapsed = time.monotonic() - start
    assert 0.45 <= rec.duration <= 0.5
    assert elapsed >= 0.45, f"real-time replay of 0.5 s took only {elapsed:.2f} s"


def test_replay_of_a_real_dataset_file(data_dir):
    files = sorted((data_dir / "utkinect").rglob("*.txt"))
    files = [f for f in files if f.name.startswith("joints")] or files
    try:
        formats.detect(files[0])
    except Exception:
        pytest.skip("no reader for UTKinect files in this checkout yet")
    rec = record(ReplaySource(files[0], realtime=False), seconds=2.0)
    assert rec.n_frames > 10 and rec.duration <= 2.0


def test_replay_of_a_missing_file_names_it(tmp_path):
    with pytest.raises(Exception, match="no such file"):
        record(ReplaySource(tmp_path / "nope.csv", realtime=False), seconds=1)


def test_simulator_source_runs_past_one_block():
    source = SimulatorSource("squat", device="kinect1", reps_per_block=1, realtime=False, seed=3)
    rec = record(source, seconds=20.0)
    assert 19.9 <= rec.duration <= 20.0
    assert np.all(np.diff(rec.t) > 0)
    assert rec.meta.device == "kinect1" and rec.meta.exercise == "squat"


def test_kinect_v2_without_sdk_says_what_to_install():
    with pytest.raises(DeviceUnavailable, match=r"Windows.*pykinect2.*linux|Windows.*pykinect2"):
        KinectV2Source().open()


def test_azure_kinect_without_sdk_says_what_to_install():
    with pytest.raises(DeviceUnavailable, match=r"pyk4a.*Body Tracking|Body Tracking.*pyk4a"):
        AzureKinectSource().open()


def test_make_source_refuses_wrong_combinations():
    with pytest.raises(ValueError, match="needs a file"):
        make_source("replay")
    with pytest.raises(ValueError, match="only for the replay"):
        make_source("simulator", file="x.csv")
    with pytest.raises(ValueError, match="known sources"):
        make_source("thermal_camera")
    with pytest.raises(ValueError, match="not both"):
        make_source("webcam", file="x.mp4", camera=1)
    with pytest.raises(ValueError, match="only for the webcam"):
        make_source("replay", file="x.csv", camera=1)


def test_record_refuses_nonpositive_seconds(session_csv):
    with pytest.raises(ValueError, match="seconds must be a positive"):
        record(ReplaySource(session_csv[0], realtime=False), seconds=0)
