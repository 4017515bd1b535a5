"""KERAAL Kinect v2 reader, on the real files in ../shared/data/keraal."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from kinect_agent import cli, formats, skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats import keraal, skeleton_csv
from kinect_agent.recording import Recording


def _files(data_dir: Path) -> list[Path]:
    root = data_dir / "keraal"
    files = sorted(root.glob("kinect_vicon_pairs/*Kinect*.txt")) + sorted(
        root.glob("kinect_gmm_examples/*/SkeletonSequence*.txt")
    )
    assert files, "no KERAAL Kinect files found"
    return files


def test_every_file_reads_with_plausible_anatomy(data_dir: Path) -> None:
    for path in _files(data_dir):
        rec = keraal.read(path)
        assert rec.meta.device == "kinect2" and rec.meta.extra["rate_assumed"] is True
        assert rec.n_frames > 100, path
        assert np.all(np.diff(rec.t) > 0), path
        head_up = rec.positions[:, skeleton.INDEX["HEAD"], 1] > rec.positions[:, skeleton.INDEX["ROOT"], 1]
        assert head_up.mean() > 0.9, f"{path}: HEAD above ROOT in only {head_up.mean():.2f} of frames"
        arm = np.nanmedian(rec.segment_lengths()[:, skeleton.SEGMENT_NAMES.index("ARM_UP_R")])
        assert 0.2 < arm < 0.4, f"{path}: upper-arm median {arm:.3f} m"


def test_line_count_and_time_base(data_dir: Path) -> None:
    path = _files(data_dir)[0]
    rec = keraal.read(path)
    lines = [line.split() for line in path.read_text().splitlines() if line.strip()]
    assert rec.n_frames == len(lines)
    np.testing.assert_allclose(rec.t, np.arange(len(lines)) / 30.0)
    # NECK comes from SpineShoulder, joint 20: fields 140..142.
    np.testing.assert_allclose(rec.positions[0, skeleton.INDEX["NECK"]], np.array(lines[0][140:143], dtype=float))
    np.testing.assert_allclose(rec.positions[0, skeleton.INDEX["HEAD"]], np.array(lines[0][21:24], dtype=float))


def test_file_name_fields(data_dir: Path) -> None:
    rec = keraal.read(data_dir / "keraal" / "kinect_vicon_pairs" / "G3-Kinect-CTK-P1T1-Unknown-C-0.txt")
    assert rec.meta.exercise == "CTK" and rec.meta.subject == "P1T1"


def test_detect_picks_keraal(data_dir: Path) -> None:
    for path in _files(data_dir):
        assert formats.detect(path).NAME == "keraal", path


def test_sniff_rejects_skeleton_csv(tmp_path: Path, rng: np.random.Generator) -> None:
    path = tmp_path / "SkeletonSequence1.csv"
    skeleton_csv.write(Recording.from_positions(np.arange(3) / 30, rng.normal(size=(3, 20, 3))), path)
    assert not keraal.sniff(path, path.read_bytes()[:8192])


def test_convert_to_csv_keeps_frame_count(data_dir: Path, tmp_path: Path) -> None:
    for path in (_files(data_dir)[0], _files(data_dir)[-1]):
        out = tmp_path / "o.csv"
        assert cli.main(["convert", str(path), "-o", str(out)]) == 0
        assert skeleton_csv.read(out).n_frames == keraal.read(path).n_frames


def _bad_copy(data_dir: Path, tmp_path: Path, edit) -> Path:
    lines = _files(data_dir)[0].read_text().splitlines()[:6]
    lines[2] = edit(lines[2])
    path = tmp_path / "G3-Kinect-CTK-P1T1-Unknown-C-0.txt"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_short_line_names_file_and_line(data_dir: Path, tmp_path: Path) -> None:
    path = _bad_copy(data_dir, tmp_path, lambda line: " ".join(line.split()[:40]))
    with pytest.raises(FormatError) as info:
        keraal.read(path)
    assert info.value.line == 3 and info.value.path == str(path) and "175" in info.value.message


def test_text_in_number_names_file_and_line(data_dir: Path, tmp_path: Path) -> None:
    path = _bad_copy(data_dir, tmp_path, lambda line: "x1.5 " + " ".join(line.split()[1:]))
    with pytest.raises(FormatError) as info:
        keraal.read(path)
    assert info.value.line == 3 and "'x1.5'" in info.value.message and "field 1" in info.value.message


def test_convert_of_bad_file_returns_2_without_output(data_dir: Path, tmp_path: Path) -> None:
    path = _bad_copy(data_dir, tmp_path, lambda line: "x1.5 " + " ".join(line.split()[1:]))
    out = tmp_path / "o.csv"
    assert cli.main(["convert", str(path), "-o", str(out)]) == 2
    assert not out.exists() and list(tmp_path.glob("*o.csv*")) == []
