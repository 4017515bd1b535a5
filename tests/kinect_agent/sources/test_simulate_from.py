"""`kinect-agent simulate --from FILE`: every dataset's motion as the truth a simulated Kinect measures."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from kinect_agent import cli, skeleton
from kinect_agent.formats import skeleton_csv
from kinect_agent.sources.mocap_truth import heading_deg
from kinect_agent.sources.motions import CAMERA_HEIGHT_M, SUBJECT_DISTANCE_M
from tests.kinect_agent.formats.test_convert_all import DATASET_FILES

FILES = sorted({relative for relative, _ in DATASET_FILES})


@pytest.mark.parametrize("relative", FILES)
@pytest.mark.parametrize("view", [0, 60])
def test_every_dataset_drives_the_simulated_kinect(data_dir: Path, tmp_path: Path, relative: str, view: int) -> None:
    measured_path, truth_path = tmp_path / "measured.csv", tmp_path / "truth.csv"
    args = ["simulate", "--from", str(data_dir / relative), "--view", str(view), "--seed", "3"]
    assert cli.main([*args, "-o", str(measured_path), "--truth", str(truth_path)]) == 0
    measured, truth = skeleton_csv.read(measured_path), skeleton_csv.read(truth_path)
    assert measured.n_frames == truth.n_frames > 10
    np.testing.assert_allclose(np.diff(truth.t), 1 / 30, atol=1e-4)
    assert np.isfinite(truth.positions).all()
    # facing the camera (−z, heading 180°) turned by the view angle, on the floor, in front of the camera
    turn = (heading_deg(truth.positions) - 180.0 - view + 180.0) % 360.0 - 180.0
    assert abs(turn) < 20, f"{relative}: heading off by {turn:.0f} deg"
    feet = truth.positions[:, [skeleton.INDEX["ANK_L"], skeleton.INDEX["ANK_R"]], 1]
    assert abs(np.percentile(feet, 1) + CAMERA_HEIGHT_M) < 0.1
    assert abs(np.mean(truth.positions[:, 0, 2]) - SUBJECT_DISTANCE_M) < 0.05
    # the Kinect errors: centimetres, not metres, away from the truth where tracked
    err = np.linalg.norm(measured.positions - truth.positions, axis=-1)
    assert 0.01 < np.nanmedian(err) < 0.25


def test_from_and_exercise_together_are_refused(data_dir: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "m.csv"
    code = cli.main(["simulate", "--from", str(data_dir / FILES[0]), "--exercise", "squat", "-o", str(out)])
    assert code == 2 and "--from" in capsys.readouterr().err and not out.exists()


def test_neither_motion_is_refused(tmp_path: Path, capsys) -> None:
    assert cli.main(["simulate", "-o", str(tmp_path / "m.csv")]) == 2
    assert "--exercise and --reps, or --from FILE" in capsys.readouterr().err
