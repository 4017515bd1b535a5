"""Tests of the UI-PRMD Kinect reader on the real recordings in ../shared/data/ui-prmd."""

from __future__ import annotations

import gzip
import shutil
from pathlib import Path

import numpy as np
import pytest

from kinect_agent import cli, skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats import ui_prmd

KINECT = Path("ui-prmd") / "Segmented Movements" / "Kinect"
EPISODE = "m01_s01_e01"


def _positions(data_dir: Path, episode: str = EPISODE) -> Path:
    return data_dir / KINECT / "Positions" / f"{episode}_positions.txt.gz"


def _copy_episode(data_dir: Path, tmp_path: Path, angles: bool = True) -> Path:
    """Copies one episode into tmp_path/Kinect/{Positions,Angles}; returns the positions file."""
    for kind, suffix in (("Positions", "positions"), ("Angles", "angles")):
        (tmp_path / "Kinect" / kind).mkdir(parents=True)
        if kind == "Positions" or angles:
            name = f"{EPISODE}_{suffix}.txt.gz"
            shutil.copy(data_dir / KINECT / kind / name, tmp_path / "Kinect" / kind / name)
    return tmp_path / "Kinect" / "Positions" / f"{EPISODE}_positions.txt.gz"


def test_one_episode_reads_with_metadata(data_dir: Path) -> None:
    rec = ui_prmd.read(_positions(data_dir))
    assert rec.n_frames > 30
    assert np.all(np.diff(rec.t) > 0)
    assert rec.meta.device == "kinect2" and rec.meta.rate_hz == 30.0
    assert (rec.meta.exercise, rec.meta.subject, rec.meta.extra["episode"]) == ("m01", "s01", "e01")


def test_segment_lengths_are_plausible(data_dir: Path) -> None:
    rec = ui_prmd.read(_positions(data_dir, "m07_s01_e01"))
    lengths = dict(zip(skeleton.SEGMENT_NAMES, np.nanmedian(rec.segment_lengths(), axis=0), strict=True))
    for name in ("ARM_UP_L", "ARM_UP_R", "ARM_LO_L", "ARM_LO_R"):
        assert 0.2 < lengths[name] < 0.4, f"{name} = {lengths[name]:.3f} m"
    for name in ("LEG_UP_L", "LEG_UP_R", "LEG_LO_L", "LEG_LO_R"):
        assert 0.25 < lengths[name] < 0.55, f"{name} = {lengths[name]:.3f} m"


def test_frame_is_kinect_camera_space(data_dir: Path) -> None:
    rec = ui_prmd.read(_positions(data_dir))
    p = rec.positions
    head, root = p[:, skeleton.INDEX["HEAD"]], p[:, skeleton.INDEX["ROOT"]]
    assert np.all(head[:, 1] > root[:, 1] + 0.3), "y must point up"
    assert np.all(root[:, 2] > 1.0), "the subject stands in front of the camera (z > 0)"
    assert np.all(p[:, skeleton.INDEX["SHO_L"], 0] < p[:, skeleton.INDEX["SHO_R"], 0]), "left is -x facing the camera"


def test_hand_copies_wrist_and_is_inferred(data_dir: Path) -> None:
    rec = ui_prmd.read(_positions(data_dir))
    np.testing.assert_array_equal(rec.positions[:, skeleton.INDEX["HAN_L"]], rec.positions[:, skeleton.INDEX["WRI_L"]])
    assert np.all(rec.state[:, skeleton.INDEX["HAN_L"]] == skeleton.INFERRED)
    assert np.all(rec.state[:, skeleton.INDEX["WRI_L"]] == skeleton.TRACKED)


def test_ten_episodes_concatenate(data_dir: Path) -> None:
    rec = ui_prmd.read_episodes(data_dir / KINECT / "Positions", movement="m01", subject="s01")
    starts = rec.meta.extra["part_start_s"]
    assert len(starts) == 10
    assert rec.meta.extra["episode"] == [f"e{i:02d}" for i in range(1, 11)]
    assert np.all(np.diff(rec.t) > 0)
    single = ui_prmd.read(_positions(data_dir))
    np.testing.assert_allclose(rec.positions[: single.n_frames], single.positions)


def test_folder_with_several_subjects_is_refused(data_dir: Path) -> None:
    with pytest.raises(FormatError, match="read_episodes"):
        ui_prmd.read(data_dir / KINECT / "Positions")


def test_folder_with_one_episode_reads(data_dir: Path, tmp_path: Path) -> None:
    _copy_episode(data_dir, tmp_path)
    assert ui_prmd.sniff(tmp_path / "Kinect", b"")
    rec = ui_prmd.read(tmp_path / "Kinect")
    assert len(rec.meta.extra["part_start_s"]) == 1


def test_missing_angles_file_is_named(data_dir: Path, tmp_path: Path) -> None:
    positions = _copy_episode(data_dir, tmp_path, angles=False)
    with pytest.raises(FormatError, match=f"{EPISODE}_angles.txt.gz") as info:
        ui_prmd.read(positions)
    assert "missing" in info.value.message


def test_truncated_row_names_line(data_dir: Path, tmp_path: Path) -> None:
    positions = _copy_episode(data_dir, tmp_path)
    lines = gzip.open(positions, "rt").read().splitlines()
    lines[4] = ",".join(lines[4].split(",")[:40])
    with gzip.open(positions, "wt") as f:
        f.write("\n".join(lines) + "\n")
    with pytest.raises(FormatError, match="expected 66 columns") as info:
        ui_prmd.read(positions)
    assert info.value.line == 5


def test_plain_text_files_read(data_dir: Path, tmp_path: Path) -> None:
    positions = _copy_episode(data_dir, tmp_path)
    for gz in (positions, tmp_path / "Kinect" / "Angles" / f"{EPISODE}_angles.txt.gz"):
        gz.with_suffix("").write_text(gzip.open(gz, "rt").read())
        gz.unlink()
    rec = ui_prmd.read(positions.with_suffix(""))
    np.testing.assert_allclose(rec.positions, ui_prmd.read(_positions(data_dir)).positions)


def test_sniff_by_name() -> None:
    assert ui_prmd.sniff(Path("m01_s01_e01_positions.txt.gz"), b"")
    assert ui_prmd.sniff(Path("m10_s09_e10_positions.txt"), b"")
    assert not ui_prmd.sniff(Path("m01_s01_e01_angles.txt"), b"")


def test_cli_converts_to_csv(data_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "out.csv"
    assert cli.main(["convert", str(_positions(data_dir)), "-o", str(out)]) == 0
    assert out.stat().st_size > 0


def test_incorrect_episode_reads(data_dir: Path) -> None:
    folder = data_dir / "ui-prmd" / "Incorrect Segmented Movements" / "Kinect" / "Positions"
    rec = ui_prmd.read(folder / "m01_s01_e01_positions_inc.txt.gz")
    assert rec.meta.extra["incorrect"] is True
    assert np.all(rec.positions[:, skeleton.INDEX["HEAD"], 1] > rec.positions[:, skeleton.INDEX["ROOT"], 1])
