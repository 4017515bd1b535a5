"""UTKinect-Action3D reader and the Kinect v1/v2 joint mapping, on the real files in ../shared/data/utkinect."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from kinect_agent import cli, formats, skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats import kinect_joints, skeleton_csv, utkinect


def _files(data_dir: Path) -> list[Path]:
    files = sorted((data_dir / "utkinect").glob("joints_*.txt"))
    assert files, "no UTKinect joints files found"
    return files


def test_v1_order_is_our_order() -> None:
    np.testing.assert_array_equal(kinect_joints.source_indices("kinect1"), np.arange(skeleton.J))


def test_v2_mapping_uses_spine_shoulder_for_neck() -> None:
    index = kinect_joints.source_indices("kinect2")
    assert kinect_joints.KINECT_V2_JOINTS[index[skeleton.INDEX["NECK"]]] == "SpineShoulder"
    assert kinect_joints.KINECT_V2_JOINTS[index[skeleton.INDEX["ROOT"]]] == "SpineBase"
    assert len(set(index.tolist())) == skeleton.J


def test_to_skeleton_keeps_state_and_marks_nan(rng: np.random.Generator) -> None:
    raw = rng.normal(size=(4, 25, 3))
    raw[1, 20] = np.nan  # SpineShoulder -> NECK
    state = np.full((4, 25), 1)
    positions, out_state = kinect_joints.to_skeleton(raw, "kinect2", state)
    assert positions.shape == (4, 20, 3) and out_state.shape == (4, 20)
    assert out_state[1, skeleton.INDEX["NECK"]] == skeleton.NOT_TRACKED
    assert np.all(out_state[0] == skeleton.INFERRED)
    np.testing.assert_array_equal(positions[:, skeleton.INDEX["HEAD"]], raw[:, 3])


def test_to_skeleton_rejects_wrong_shape() -> None:
    with pytest.raises(ValueError, match=r"\(T, 20, 3\)"):
        kinect_joints.to_skeleton(np.zeros((3, 25, 3)), "kinect1")


def test_every_file_reads_with_plausible_anatomy(data_dir: Path) -> None:
    for path in _files(data_dir):
        rec = utkinect.read(path)
        assert rec.meta.device == "kinect1" and rec.meta.rate_hz == 30
        assert rec.n_frames > 100, path
        assert np.all(np.diff(rec.t) > 0), path
        head_up = rec.positions[:, skeleton.INDEX["HEAD"], 1] > rec.positions[:, skeleton.INDEX["ROOT"], 1]
        assert head_up.mean() > 0.9, f"{path}: HEAD above ROOT in only {head_up.mean():.2f} of frames"
        arm = np.nanmedian(rec.segment_lengths()[:, skeleton.SEGMENT_NAMES.index("ARM_UP_L")])
        assert 0.2 < arm < 0.4, f"{path}: upper-arm median {arm:.3f} m"


def test_time_is_frame_id_over_30(data_dir: Path) -> None:
    path = _files(data_dir)[0]
    rec = utkinect.read(path)
    first_id = int(path.read_text().split()[0])
    assert rec.t[0] == pytest.approx(first_id / 30.0)
    steps = np.round(np.diff(rec.t) * 30.0)
    assert steps.min() >= 1 and steps.max() > 1, "gaps in frame ids must stay time gaps"


def test_repeated_frame_ids_keep_first(data_dir: Path) -> None:
    counts = {p.name: utkinect.read(p).meta.extra["dropped_duplicate_frames"] for p in _files(data_dir)}
    assert max(counts.values()) > 0, counts
    path = _files(data_dir)[0]
    lines = [line.split() for line in path.read_text().splitlines() if line.strip()]
    ids = [int(cells[0]) for cells in lines]
    rec = utkinect.read(path)
    assert rec.n_frames == len(set(ids))
    assert rec.n_frames + counts[path.name] == len(lines)
    np.testing.assert_allclose(rec.positions[0].ravel(), np.array(lines[0][1:], dtype=float))


def test_exact_duplicate_lines_are_dropped(data_dir: Path, tmp_path: Path) -> None:
    lines = _files(data_dir)[0].read_text().splitlines()[:5]
    path = tmp_path / "joints_s09_e01.txt"
    path.write_text("\n".join([lines[0], *lines]) + "\n")
    rec = utkinect.read(path)
    assert rec.meta.extra["dropped_duplicate_lines"] == 1
    assert rec.meta.subject == "s09"


def test_subject_and_actions_from_label_file(data_dir: Path) -> None:
    rec = utkinect.read(data_dir / "utkinect" / "joints_s01_e01.txt")
    assert rec.meta.subject == "s01"
    assert rec.meta.extra["actions"]["walk"] == [252, 390]
    assert len(rec.meta.extra["actions"]) == 10


def test_an_action_marked_nan_is_left_out_and_named(data_dir: Path, tmp_path: Path) -> None:
    """actionLabel.txt has `carry:  NaN NaN` for s10_e02 (not done in that sequence): the recording still reads."""
    import shutil

    shutil.copy(data_dir / "utkinect" / "actionLabel.txt", tmp_path / "actionLabel.txt")
    shutil.copy(data_dir / "utkinect" / "joints_s01_e01.txt", tmp_path / "joints_s10_e02.txt")
    rec = utkinect.read(tmp_path / "joints_s10_e02.txt")
    assert rec.meta.extra["actions_not_performed"] == ["carry"]
    assert "carry" not in rec.meta.extra["actions"] and rec.meta.extra["actions"]["walk"] == [96, 220]
    assert len(rec.meta.extra["actions"]) == 9


def test_detect_picks_utkinect(data_dir: Path) -> None:
    for path in _files(data_dir):
        assert formats.detect(path).NAME == "utkinect", path


def test_detect_without_file_name_hint(data_dir: Path, tmp_path: Path) -> None:
    path = tmp_path / "recording.txt"
    path.write_text(_files(data_dir)[0].read_text())
    assert formats.detect(path).NAME == "utkinect"


def test_sniff_rejects_skeleton_csv(tmp_path: Path, rng: np.random.Generator) -> None:
    from kinect_agent.recording import Recording

    path = tmp_path / "joints_s01_e01.csv"
    skeleton_csv.write(Recording.from_positions(np.arange(3) / 30, rng.normal(size=(3, 20, 3))), path)
    assert not utkinect.sniff(path, path.read_bytes()[:8192])
    assert formats.detect(path).NAME == "csv"


def test_convert_to_csv_keeps_frame_count(data_dir: Path, tmp_path: Path) -> None:
    path = _files(data_dir)[0]
    out = tmp_path / "o.csv"
    assert cli.main(["convert", str(path), "-o", str(out)]) == 0
    back = skeleton_csv.read(out)
    assert back.n_frames == utkinect.read(path).n_frames


def _bad_copy(data_dir: Path, tmp_path: Path, edit) -> Path:
    lines = _files(data_dir)[0].read_text().splitlines()[:6]
    lines[3] = edit(lines[3])
    path = tmp_path / "joints_s01_e01.txt"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_short_line_names_file_and_line(data_dir: Path, tmp_path: Path) -> None:
    path = _bad_copy(data_dir, tmp_path, lambda line: " ".join(line.split()[:40]))
    with pytest.raises(FormatError) as info:
        utkinect.read(path)
    assert info.value.line == 4 and info.value.path == str(path)
    assert "61" in info.value.message and "40" in info.value.message


def test_text_in_number_names_file_and_line(data_dir: Path, tmp_path: Path) -> None:
    path = _bad_copy(data_dir, tmp_path, lambda line: line.replace(line.split()[5], "abc", 1))
    with pytest.raises(FormatError) as info:
        utkinect.read(path)
    assert info.value.line == 4 and "'abc'" in info.value.message


def test_convert_of_bad_file_returns_2_without_output(data_dir: Path, tmp_path: Path) -> None:
    path = _bad_copy(data_dir, tmp_path, lambda line: " ".join(line.split()[:40]))
    out = tmp_path / "o.csv"
    assert cli.main(["convert", str(path), "-o", str(out)]) == 2
    assert not out.exists() and list(tmp_path.glob("*o.csv*")) == []


def test_decreasing_frame_id_names_line(data_dir: Path, tmp_path: Path) -> None:
    lines = _files(data_dir)[0].read_text().splitlines()[:6]
    path = tmp_path / "joints_s01_e01.txt"
    path.write_text("\n".join([*lines[:4], "1 " + " ".join(lines[4].split()[1:])]) + "\n")
    with pytest.raises(FormatError, match="must not decrease") as info:
        utkinect.read(path)
    assert info.value.line == 5
