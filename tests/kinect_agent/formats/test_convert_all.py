"""`kinect-agent convert` on one real file of every dataset in ../shared/data (and every HDM05 motion class)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from kinect_agent import cli, formats, skeleton
from kinect_agent.formats import session_file, skeleton_csv

# (dataset file relative to ../shared/data, expected reader NAME)
DATASET_FILES = [
    ("ui-prmd/Segmented Movements/Kinect/Positions/m01_s01_e01_positions.txt.gz", "ui_prmd"),
    ("ui-prmd/Incorrect Segmented Movements/Kinect/Positions/m01_s01_e01_positions_inc.txt.gz", "ui_prmd"),
    ("ui-prmd/Segmented Movements/Vicon/Positions/m07_s01_e02_positions.txt.gz", "ui_prmd_vicon"),
    ("ui-prmd/Incorrect Segmented Movements/Vicon/Positions/m01_s01_e01_positions_inc.txt.gz", "ui_prmd_vicon"),
    ("utkinect/joints_s01_e01.txt", "utkinect"),
    ("keraal/kinect_vicon_pairs/G3-Kinect-CTK-P1T1-Unknown-C-0.txt", "keraal"),
    ("keraal/kinect_gmm_examples/Assis1Maxime/SkeletonSequence1.txt", "keraal"),
    ("keraal/kinect_vicon_pairs/G3-Vicon-CTK-P1T1-Unknown-C-0.txt", "keraal_vicon"),
    ("cmu-mocap/13_29.bvh", "bvh"),
    ("hdm05/squat1Reps/HDM_bd_squat1Reps_001_120.amc", "amc"),
    ("hdm05/kickLFront1Reps/HDM_bk_kickLFront1Reps_007_120.amc", "amc"),
    ("hdm05/elbowToKnee1RepsLelbowStart/HDM_bd_elbowToKnee1RepsLelbowStart_001_120.amc", "amc"),
    ("hdm05/rotateArmsBothBackward1Reps/HDM_bk_rotateArmsBothBackward1Reps_005_120.amc", "amc"),
]


@pytest.mark.parametrize(("relative", "reader"), DATASET_FILES, ids=[r for r, _ in DATASET_FILES])
def test_convert_to_csv_and_session(data_dir: Path, tmp_path: Path, relative: str, reader: str) -> None:
    path = data_dir / relative
    assert formats.detect(path).NAME == reader
    direct = formats.read(path)
    csv_out, khs_out = tmp_path / "out.csv", tmp_path / "out.khs"
    assert cli.main(["convert", str(path), "-o", str(csv_out)]) == 0
    assert cli.main(["convert", str(path), "-o", str(khs_out)]) == 0
    # Skeleton CSV keeps 1e-5 m; the session file rounds positions to its 2**-13 m grid.
    for back, atol in ((skeleton_csv.read(csv_out), 1e-5), (session_file.read(khs_out), session_file.GRID_M)):
        assert back.n_frames == direct.n_frames > 10
        assert back.positions.shape == (direct.n_frames, skeleton.J, 3)
        np.testing.assert_allclose(back.t, direct.t, atol=1e-5, err_msg=relative)
        np.testing.assert_allclose(back.positions, direct.positions, atol=atol, err_msg=relative)
    tracked = np.isfinite(direct.positions[..., 1])
    assert tracked.mean() > 0.9, f"{relative}: only {tracked.mean():.2f} of joint-frames present"
    head_up = direct.positions[:, skeleton.INDEX["HEAD"], 1] > direct.positions[:, skeleton.INDEX["ROOT"], 1]
    assert np.nanmean(head_up) > 0.9, f"{relative}: y is not up"


def test_unrecognised_file_fails_clearly_without_output(tmp_path: Path, capsys) -> None:
    path = tmp_path / "notes.txt"
    path.write_text("not a recording\n")
    out = tmp_path / "out.csv"
    assert cli.main(["convert", str(path), "-o", str(out)]) == 2
    assert path.name in capsys.readouterr().err
    assert not out.exists() and sorted(tmp_path.iterdir()) == [path]
