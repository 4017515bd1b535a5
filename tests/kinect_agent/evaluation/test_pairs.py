"""Folder pairing rules of `kinect-agent evaluate --pairs` and the choice of scored joints."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.evaluation.pairs import find_pairs, scored_joints, well_estimated
from kinect_agent.recording import Recording
from tests.kinect_agent.evaluation._simulated import simulated_pair, write_pair


def test_csv_pairs_are_found_by_name_and_side_files_skipped(tmp_path: Path) -> None:
    kinect, mocap, _ = simulated_pair(0, 0.1, reps=2)
    k, m = write_pair(tmp_path, "trial1", kinect, mocap)
    (tmp_path / "notes.txt").write_text("not a recording", encoding="utf-8")
    (tmp_path / "lonely_kinect.csv").write_bytes(k.read_bytes())  # no mocap twin
    assert find_pairs(tmp_path) == [(k, m)]


def test_kinect_and_vicon_folders_are_paired(tmp_path: Path) -> None:
    kinect, mocap, _ = simulated_pair(1, 0.1, reps=2)
    for side, rec in (("Kinect", kinect), ("Vicon", mocap)):
        (tmp_path / side / "Positions").mkdir(parents=True)
        write_pair(tmp_path / side / "Positions", "e01", rec, rec)
    pairs = find_pairs(tmp_path)
    assert (tmp_path / "Kinect/Positions/e01_kinect.csv", tmp_path / "Vicon/Positions/e01_kinect.csv") in pairs


def test_a_missing_folder_is_named(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="nowhere"):
        find_pairs(tmp_path / "nowhere")


def test_scored_joints_follow_the_mocap_format() -> None:
    rec = Recording(np.arange(4) / 30.0, np.zeros((4, skeleton.J, 3)), np.full((4, skeleton.J), 2, np.int8))
    rec.positions[:, skeleton.INDEX["HEAD"]] = np.nan
    csv_joints = scored_joints("csv", rec)
    assert not csv_joints[skeleton.INDEX["HEAD"]] and csv_joints.sum() == skeleton.J - 1
    keraal = well_estimated(["ELB_L"])
    assert not keraal[skeleton.INDEX["ELB_L"]] and keraal[skeleton.INDEX["ROOT"]] and not keraal[skeleton.INDEX["HEAD"]]
    ui = scored_joints("ui_prmd_vicon", rec)
    assert not ui[skeleton.INDEX["KNE_L"]] and ui[skeleton.INDEX["WRI_R"]]
