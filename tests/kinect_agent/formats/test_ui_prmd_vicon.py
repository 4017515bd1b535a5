"""UI-PRMD Vicon reader, on every Vicon file in ../shared/data/ui-prmd (s01, correct and incorrect)."""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pytest

from kinect_agent import cli, formats, skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats import ui_prmd, ui_prmd_vicon

SEGMENT_RANGES_M = {
    "ARM_UP": (0.22, 0.38), "ARM_LO": (0.20, 0.32), "HAND": (0.04, 0.15), "PELVIC": (0.08, 0.18),
    "LEG_UP": (0.30, 0.50), "LEG_LO": (0.33, 0.52), "FOOT": (0.08, 0.22),
}  # fmt: skip


def _files(data_dir: Path) -> list[Path]:
    files = sorted((data_dir / "ui-prmd").glob("*/Vicon/Positions/*_positions*.txt.gz"))
    assert len(files) >= 100, f"expected the UI-PRMD Vicon files, found {len(files)}"
    return files


def test_every_file_has_the_plug_in_gait_layout(data_dir: Path) -> None:
    """Head and neck above the pelvis, standing at the start, the pelvis facing -z, plausible segment lengths."""
    i = skeleton.INDEX
    tracked = []
    for path in _files(data_dir):
        rec = ui_prmd_vicon.read(path)
        y = rec.positions[..., 1]
        assert np.all(y[:, i["HEAD"]] > y[:, i["ROOT"]]) and np.all(y[:, i["NECK"]] > y[:, i["ROOT"]]), path.name
        assert y[0, i["HEAD"]] > y[0, i["NECK"]], f"{path.name}: head below neck in the first frame"
        assert y[0, i["ROOT"]] > y[0, i["KNE_L"]] > y[0, i["ANK_L"]], f"{path.name}: first frame not standing"
        left = rec.positions[:, i["HIP_L"]] - rec.positions[:, i["HIP_R"]]
        facing = np.cross(left, [0.0, 1.0, 0.0])
        # Within 90 degrees of -z (the inline lunge turns the pelvis by about 60 degrees).
        assert np.median(facing[:, 2]) < 0.0, f"{path.name}: the pelvis does not face -z"
        seg = rec.segment_lengths()
        for k, name in enumerate(skeleton.SEGMENT_NAMES):
            present = seg[:, k][np.isfinite(seg[:, k])]
            if present.size == 0:  # a marker lost for the whole file (m03_s01_e01: LTOE)
                continue
            lo, hi = SEGMENT_RANGES_M[name[:-2]]
            value = float(np.median(present))
            assert lo <= value <= hi, f"{path.name} {name}: {value:.3f} m outside {lo}-{hi} m"
        tracked.append(np.mean(rec.tracked()))
    assert np.mean(tracked) > 0.97, f"only {np.mean(tracked):.3f} of joint-frames present"


def test_shoulder_abduction_raises_one_arm(data_dir: Path) -> None:
    """m07 (standing shoulder abduction): a hand rises above the head, the other stays below the hip's height + 0.3."""
    rec = ui_prmd_vicon.read(data_dir / "ui-prmd/Segmented Movements/Vicon/Positions/m07_s01_e01_positions.txt.gz")
    y = rec.positions[..., 1]
    i = skeleton.INDEX
    top = max(y[:, i["HAN_L"]].max(), y[:, i["HAN_R"]].max())
    assert top > y[:, i["HEAD"]].max(), "no hand above the head in shoulder abduction"


def test_markers_and_metadata(data_dir: Path) -> None:
    path = data_dir / "ui-prmd/Incorrect Segmented Movements/Vicon/Positions/m01_s01_e01_positions_inc.txt.gz"
    rec = ui_prmd_vicon.read(path)
    raw = np.loadtxt(gzip.open(path, "rt"), delimiter=",").reshape(-1, 39, 3)
    assert rec.n_frames == len(raw) and rec.meta.extra["incorrect"] and rec.meta.exercise == "m01"
    head_mm = raw[:, :4].mean(axis=1)
    np.testing.assert_allclose(rec.positions[:, skeleton.INDEX["HEAD"]], head_mm[:, [1, 2, 0]] * [-1, 1, -1] / 1000)
    assert rec.rate_hz == 100.0 and rec.meta.extra["rate_assumed"]


def test_missing_markers_are_not_tracked(data_dir: Path) -> None:
    """m03_s01_e01 starts with RBHD, LTOE, RTHI at 0,0,0: HEAD uses the 3 other head markers, FOO_L is lost."""
    rec = ui_prmd_vicon.read(data_dir / "ui-prmd/Segmented Movements/Vicon/Positions/m03_s01_e01_positions.txt.gz")
    assert {"RBHD", "LTOE", "RTHI"} <= set(rec.meta.extra["missing_markers"])
    assert rec.state[0, skeleton.INDEX["FOO_L"]] == skeleton.NOT_TRACKED
    assert np.all(np.isfinite(rec.positions[:, skeleton.INDEX["HEAD"]]))


def test_detect_picks_vicon_or_kinect_by_columns(data_dir: Path) -> None:
    base = data_dir / "ui-prmd/Segmented Movements"
    assert formats.detect(base / "Vicon/Positions/m01_s01_e01_positions.txt.gz") is ui_prmd_vicon
    assert formats.detect(base / "Kinect/Positions/m01_s01_e01_positions.txt.gz") is ui_prmd


def test_bad_row_names_line_and_convert_leaves_nothing(data_dir: Path, tmp_path: Path) -> None:
    source = data_dir / "ui-prmd/Segmented Movements/Vicon/Positions/m01_s01_e01_positions.txt.gz"
    lines = gzip.open(source, "rt").read().splitlines()[:5]
    lines[3] = ",".join(lines[3].split(",")[:100])
    path = tmp_path / source.name
    with gzip.open(path, "wt") as f:
        f.write("\n".join(lines) + "\n")
    with pytest.raises(FormatError) as info:
        ui_prmd_vicon.read(path)
    assert info.value.line == 4 and "expected 117 columns" in info.value.message
    out = tmp_path / "o.csv"
    assert cli.main(["convert", str(path), "-o", str(out), "--format", "ui_prmd_vicon"]) == 2
    assert not out.exists()
