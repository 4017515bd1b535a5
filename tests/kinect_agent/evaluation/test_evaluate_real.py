"""`kinect-agent evaluate` on the real Kinect v2 / Vicon pairs in ../shared/data (KERAAL group 3, UI-PRMD s01)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from kinect_agent.cli import main

DATA = Path(__file__).resolve().parents[4] / "shared" / "data"
KERAAL = DATA / "keraal" / "kinect_vicon_pairs"
UI_PRMD = DATA / "ui-prmd" / "Segmented Movements"

pytestmark = pytest.mark.shared_data


@pytest.fixture(scope="module")
def keraal_report(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, int]:
    if not KERAAL.is_dir():
        pytest.skip(f"{KERAAL} not present")
    out = tmp_path_factory.mktemp("keraal")
    return out, main(["evaluate", "--pairs", str(KERAAL), "--out", str(out)])


def test_keraal_pairs_align(keraal_report: tuple[Path, int]) -> None:
    out, rc = keraal_report
    assert rc == 0
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert len(summary["pairs"]) == 3, summary["refused"]
    for p in summary["pairs"]:
        assert abs(p["lag_s"]) < 0.1, p  # the KERAAL files start together (bench/README.md: |lag| <= 42 ms)
        assert abs(p["lag_rms_s"] - p["lag_s"]) <= 2.0 / 30.0 + 1e-9, p
        assert p["registration_rms_mm"] < 100.0, p


def test_keraal_tables_are_in_the_papers_range(keraal_report: tuple[Path, int]) -> None:
    """Kinect 2 arm and hip joints are off by 35-65 mm after outlier removal (the paper's standing Kinect 2 table:
    50-145 mm including the calibration bias our registration absorbs), with SDs of 4-40 mm."""
    out, _ = keraal_report
    with open(out / "joint_offset_standing_clean_mm.csv", encoding="utf-8") as f:
        rows = {r["joint"]: r for r in csv.DictReader(f)}
    for joint in ("SHO_L", "SHO_R", "HIP_L", "HIP_R", "NECK"):
        assert 20.0 < float(rows[joint]["mean_0"]) < 100.0, rows[joint]
        assert 2.0 < float(rows[joint]["sd_0"]) < 50.0, rows[joint]
    assert rows["HEAD"]["mean_0"] == ""  # a Vicon target, not a joint centre: not scored


def test_keraal_report_has_the_figures(keraal_report: tuple[Path, int]) -> None:
    out, _ = keraal_report
    report = (out / "report.md").read_text(encoding="utf-8")
    for png in ("figure3_mixture.png", "figure4_angles_1.png"):
        assert (out / png).stat().st_size > 5000
        assert f"]({png})" in report


def test_ui_prmd_episodes_align_or_are_refused_with_a_reason(tmp_path: Path) -> None:
    """UI-PRMD's Kinect and Vicon episodes were segmented separately; about a third align (36 of the 100 correct
    s01 episodes); e02 of m01 is refused because its two lag estimates disagree by a second."""
    if not UI_PRMD.is_dir():
        pytest.skip(f"{UI_PRMD} not present")
    args = ["evaluate", "--out", str(tmp_path), "--no-figures", "--max-lag", "1.5"]
    for name in ("m01_s01_e01", "m01_s01_e02", "m01_s01_e04", "m04_s01_e01"):
        args += ["--kinect", str(UI_PRMD / "Kinect" / "Positions" / f"{name}_positions.txt.gz"),
                 "--mocap", str(UI_PRMD / "Vicon" / "Positions" / f"{name}_positions.txt.gz")]  # fmt: skip
    assert main(args) == 0
    summary = json.loads((tmp_path / "summary.json").read_text(encoding="utf-8"))
    assert [p["name"] for p in summary["pairs"]] == [f"{n}_positions" for n in ("m01_s01_e01", "m01_s01_e04",
                                                                                "m04_s01_e01")]  # fmt: skip
    for p in summary["pairs"]:
        assert "KNE_L" not in p["scored_joints"] and "SHO_L" in p["scored_joints"]
        assert p["registration_rms_mm"] <= 100.0
        assert abs(p["lag_rms_s"] - p["lag_s"]) <= 2.0 / 30.0 + 1e-9
    [refused] = summary["refused"]
    assert refused["name"] == "m01_s01_e02_positions"
    assert any(r.startswith("lag estimates disagree") for r in refused["reasons"])
