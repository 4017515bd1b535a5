"""`kinect-agent simulate` and `kinect-agent capture` through the real CLI entry point."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent import formats
from kinect_agent.cli import main


def test_simulate_writes_measured_and_truth(tmp_path):
    out, truth = tmp_path / "m.csv", tmp_path / "t.csv"
    argv = ["simulate", "--exercise", "sit_to_stand", "--reps", "2", "--device", "kinect1", "--view", "30",
            "--pose", "sitting", "--seed", "4", "--rate", "20", "-o", str(out), "--truth", str(truth)]  # fmt: skip
    assert main(argv) == 0
    m, t = formats.read(out), formats.read(truth)
    assert m.n_frames == t.n_frames
    np.testing.assert_allclose(np.diff(t.t), 1 / 20, atol=1e-6)
    assert np.nanmax(np.linalg.norm(m.positions - t.positions, axis=-1)) > 0.01


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--exercise", "yoga", "--reps", "2"], "known exercises: shoulder_abduction"),
        (["--exercise", "squat", "--reps", "0"], "reps must be a whole number from 1"),
        (["--exercise", "squat", "--reps", "2", "--view", "45"], "view 45 degrees is not tabled"),
        (["--exercise", "squat", "--reps", "2", "--pose", "sitting"], "squat cannot be done sitting"),
        (["--exercise", "squat", "--reps", "2", "--device", "kinect3"], "unknown device"),
    ],
)
def test_simulate_bad_arguments_write_nothing(tmp_path, capsys, args, message):
    out = tmp_path / "m.csv"
    assert main(["simulate", *args, "-o", str(out)]) == 2
    assert message in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_simulate_refuses_unknown_extension(tmp_path, capsys):
    assert main(["simulate", "--exercise", "squat", "--reps", "1", "-o", str(tmp_path / "m.txt")]) == 2
    assert "use .csv or .khs" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_capture_replay_and_simulator(tmp_path):
    sim = tmp_path / "sim.csv"
    assert main(["capture", "--source", "simulator", "--exercise", "squat", "--seconds", "3", "--fast",
                 "-o", str(sim)]) == 0  # fmt: skip
    assert 2.9 <= formats.read(sim).duration <= 3.0
    out = tmp_path / "replayed.csv"
    assert main(["capture", "--source", "replay", "--file", str(sim), "--seconds", "1", "--fast", "-o", str(out)]) == 0
    rec = formats.read(out)
    assert 0.9 <= rec.duration <= 1.0


def test_capture_hardware_without_sdk_fails_clearly_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "k.csv"
    assert main(["capture", "--source", "kinect_v2", "--seconds", "1", "-o", str(out)]) == 2
    assert "pykinect2" in capsys.readouterr().err
    assert main(["capture", "--source", "azure_kinect", "--seconds", "1", "-o", str(out)]) == 2
    assert "pyk4a" in capsys.readouterr().err
    assert not out.exists()


def test_capture_bad_arguments(tmp_path, capsys):
    out = tmp_path / "k.csv"
    assert main(["capture", "--source", "replay", "--seconds", "1", "-o", str(out)]) == 2
    assert "needs a file" in capsys.readouterr().err
    assert main(["capture", "--source", "simulator", "--seconds", "-1", "--fast", "-o", str(out)]) == 2
    assert "--seconds must be a positive" in capsys.readouterr().err
    assert main(["capture", "--source", "replay", "--file", str(tmp_path / "none.csv"), "--seconds", "1",
                 "-o", str(out)]) == 2  # fmt: skip
    assert "no such file" in capsys.readouterr().err
    assert not out.exists()
