"""BVH optical mocap reader, on the real CMU trial 13_29 in ../shared/data/cmu-mocap."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from kinect_agent import cli, formats, skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats import bvh, mocap_mapping

SEGMENT_RANGES_M = {
    "ARM_UP_L": (0.22, 0.38), "ARM_UP_R": (0.22, 0.38),
    "LEG_UP_L": (0.33, 0.55), "LEG_UP_R": (0.33, 0.55),
    "LEG_LO_L": (0.33, 0.50), "LEG_LO_R": (0.33, 0.50),
}  # fmt: skip


@pytest.fixture
def bvh_path(data_dir: Path) -> Path:
    return data_dir / "cmu-mocap" / "13_29.bvh"


@pytest.fixture
def rec(bvh_path: Path):
    return bvh.read(bvh_path)


def _lines(path: Path) -> list[str]:
    return path.read_text().splitlines(keepends=True)


def _motion_line(lines: list[str]) -> int:
    """Returns the 0-based index of the MOTION line."""
    return next(i for i, line in enumerate(lines) if line.strip() == "MOTION")


def test_frames_rate_and_metadata(rec) -> None:
    assert rec.n_frames == 4593
    assert rec.rate_hz == pytest.approx(120.0, abs=0.5)
    assert rec.meta.device == "mocap"
    assert rec.meta.extra["bvh_joints"] == 31
    assert rec.meta.extra["segments"][0]["action_name"] == "JumpJack"
    assert np.all(rec.state == skeleton.TRACKED)


def test_segment_lengths_constant_and_plausible(rec) -> None:
    lengths = rec.segment_lengths()
    sd = np.std(lengths, axis=0)
    assert np.all(sd < 1e-3), f"segment length SD (m): {dict(zip(skeleton.SEGMENT_NAMES, sd.round(5), strict=True))}"
    for name, (lo, hi) in SEGMENT_RANGES_M.items():
        value = float(np.mean(lengths[:, skeleton.SEGMENT_NAMES.index(name)]))
        assert lo <= value <= hi, f"{name} {value:.3f} m outside {lo}-{hi} m"


def test_y_is_up_in_first_frame(rec) -> None:
    y = rec.positions[0, :, 1]
    i = skeleton.INDEX
    assert y[i["HEAD"]] > y[i["ROOT"]] > y[i["ANK_L"]], (
        f"HEAD, ROOT, ANK_L heights {y[[i['HEAD'], i['ROOT'], i['ANK_L']]]}"
    )


def test_sniff_and_detect(bvh_path: Path) -> None:
    assert bvh.sniff(bvh_path, bvh_path.read_bytes()[:64])
    assert not bvh.sniff(bvh_path, b"time,ROOT_x")
    assert formats.detect(bvh_path) is bvh


def test_forward_kinematics_rotation_order() -> None:
    """Channels Zrotation Xrotation compose intrinsically as listed: R = Rz @ Rx, applied to the child offset."""
    joints = [
        bvh.Joint("root", -1, np.zeros(3), ["Zrotation", "Xrotation"], 0),
        bvh.Joint("child", 0, np.array([1.0, 0.0, 0.0])),
    ]
    world = bvh.forward_kinematics(joints, np.array([[90.0, 0.0], [90.0, 90.0], [0.0, 90.0]]))
    np.testing.assert_allclose(world[:, 1], [[0, 1, 0], [0, 1, 0], [1, 0, 0]], atol=1e-12)
    # Rz(90) @ Rx(90) applied to y: Rx takes y to z, Rz leaves z.
    joints[1].offset = np.array([0.0, 1.0, 0.0])
    world = bvh.forward_kinematics(joints, np.array([[90.0, 90.0]]))
    np.testing.assert_allclose(world[0, 1], [0, 0, 1], atol=1e-12)


def test_mapping_resolves_all_joints_of_cmu_file(rec) -> None:
    assert np.all(np.isfinite(rec.positions))
    assert mocap_mapping.resolve(["LHipJoint_End", "RHipJoint_End"])["ROOT"] == ("LHipJoint_End", "RHipJoint_End")


def test_cli_convert(bvh_path: Path, tmp_path: Path) -> None:
    out = tmp_path / "out.csv"
    assert cli.main(["convert", str(bvh_path), "-o", str(out)]) == 0
    back = formats.read(out)
    assert back.n_frames == 4593
    np.testing.assert_allclose(back.positions[0], bvh.read(bvh_path).positions[0], atol=1e-4)


def _bad(tmp_path: Path, lines: list[str]) -> Path:
    path = tmp_path / "bad.bvh"
    path.write_text("".join(lines))
    return path


def _assert_format_error(path: Path, line: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(FormatError) as info:
        bvh.read(path)
    assert info.value.path == str(path) and info.value.line == line, str(info.value)
    out = tmp_path / "out.csv"
    assert cli.main(["convert", str(path), "-o", str(out)]) != 0
    assert f"{path}:{line}:" in capsys.readouterr().err
    assert not out.exists() and not list(tmp_path.glob("*.part"))


def test_truncated_in_motion(bvh_path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = _lines(bvh_path)
    cut = _motion_line(lines) + 3 + 100  # keep 100 frames
    _assert_format_error(_bad(tmp_path, lines[:cut]), cut, tmp_path, capsys)


def test_missing_motion(bvh_path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = _lines(bvh_path)[: _motion_line(_lines(bvh_path))]
    _assert_format_error(_bad(tmp_path, lines), len(lines), tmp_path, capsys)


def test_row_with_wrong_count(bvh_path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = _lines(bvh_path)
    k = _motion_line(lines) + 3 + 10
    lines[k] = " ".join(lines[k].split()[:-1]) + "\n"
    _assert_format_error(_bad(tmp_path, lines), k + 1, tmp_path, capsys)
