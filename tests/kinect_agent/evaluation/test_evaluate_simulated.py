"""`kinect-agent evaluate` on simulated pairs: the calibrated per-joint SD and a known time offset come back."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from kinect_agent import skeleton
from kinect_agent.cli import main
from kinect_agent.evaluation import figures
from kinect_agent.evaluation.align import interpolate, measured
from kinect_agent.evaluation.pairs import PairRefused, PairSpec, align_pair
from kinect_agent.evaluation.register import register, rotation_deg
from kinect_agent.recording import Recording
from kinect_agent.sources.kinect_noise import load_tables
from tests.kinect_agent.evaluation._simulated import KINECT_HZ, simulated_pair, write_pair

SEEDS = (0, 1, 2)


def _lag(seed: int) -> float:
    return 0.31 + 0.217 * seed  # not a whole number of Kinect frames


@pytest.fixture(scope="module")
def simulated_report(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, int]:
    """Evaluates three simulated pairs (Kinect 2, standing, 0°; mocap in the camera frame) in one report."""
    pairs, out = tmp_path_factory.mktemp("pairs"), tmp_path_factory.mktemp("report")
    for seed in SEEDS:
        kinect, mocap, _ = simulated_pair(seed, _lag(seed))
        write_pair(pairs, f"sim{seed}", kinect, mocap)
    rc = main(["evaluate", "--pairs", str(pairs), "--out", str(out), "--no-registration", "--no-figures"])
    return out, rc


def test_recovers_the_calibrated_sd_per_joint(simulated_report: tuple[Path, int]) -> None:
    out, rc = simulated_report
    assert rc == 0
    with open(out / "joint_offset_standing_clean_mm.csv", encoding="utf-8") as f:
        rows = {r["joint"]: float(r["sd_0"]) for r in csv.DictReader(f)}
    calibrated = 1e3 * load_tables().offset_sd["kinect2", "standing", 0]
    recovered = np.array([rows[j] for j in skeleton.JOINTS])
    np.testing.assert_allclose(recovered, calibrated, rtol=0.10, err_msg=f"joints {skeleton.JOINTS}")


def test_recovers_the_time_offset_within_one_frame(simulated_report: tuple[Path, int]) -> None:
    out, _ = simulated_report
    pairs = json.loads((out / "summary.json").read_text(encoding="utf-8"))["pairs"]
    assert sorted(p["name"] for p in pairs) == [f"sim{s}_kinect" for s in SEEDS]
    for p in pairs:
        seed = int(p["name"][3])
        assert abs(p["lag_s"] - _lag(seed)) * KINECT_HZ < 1.0, p


def test_writes_every_table_and_a_report(simulated_report: tuple[Path, int]) -> None:
    out, _ = simulated_report
    for stage in ("raw", "clean", "pipeline"):
        assert (out / f"joint_offset_standing_{stage}_mm.csv").is_file()
        assert (out / f"bone_length_error_standing_{stage}_mm.csv").is_file()
    with open(out / "outlier_removal_gain_pct.csv", encoding="utf-8") as f:
        gain = {r["removal"]: r for r in csv.DictReader(f)}
    assert 0.0 < float(gain["mixture"]["sd_gain_0"]) < 80.0  # the simulator's tracking loss is removed
    with open(out / "error_parts_mm.csv", encoding="utf-8") as f:
        parts = list(csv.DictReader(f))
    assert {(r["stage"], r["joint"]) for r in parts} == {
        (s, j) for s in ("raw", "clean", "pipeline") for j in skeleton.JOINTS
    }
    for r in parts:
        rmse, bias, rand = (float(r[k]) for k in ("rmse_mm", "bias_mm", "random_mm"))
        assert bias > 0.0 and rand > 0.0 and abs(rmse**2 - bias**2 - rand**2) <= 0.02 * rmse**2 + 0.5, r
    report = (out / "report.md").read_text(encoding="utf-8")
    assert "sim0_kinect" in report and "## joint_offset_standing_clean_mm.csv" in report
    assert "| joint | mean_0 | sd_0 | paper_k2_mean_0 | paper_k2_sd_0 |" in report
    assert "| ROOT | " in report and "| 76.0 | 24.0 |" in report  # the paper's Kinect 2 standing 0° ROOT


def _moved(rec: Recording, R: np.ndarray, t: np.ndarray) -> Recording:
    return Recording(rec.t, rec.positions @ R.T + t, rec.state, rec.meta)


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_registration_finds_the_offset_and_the_oracle_transform(seed: int) -> None:
    """Mocap in its own frame: the lag is within one frame and the rigid fit equals the one at the true lag (the
    fit itself absorbs part of the Kinect's systematic offsets, so it is compared with that oracle fit)."""
    kinect, mocap, _ = simulated_pair(seed, _lag(seed), reps=5)
    rng = np.random.default_rng(seed)
    R = Rotation.from_rotvec(rng.uniform(0.3, 2.0) * rng.normal(size=3) / np.sqrt(3.0)).as_matrix()
    moved = _moved(mocap, R, rng.normal(size=3))
    joints = np.ones(skeleton.J, bool)
    pair = align_pair(PairSpec(Path("k"), Path("m")), kinect, moved, joints)
    assert abs(pair.alignment.lag_s - _lag(seed)) * KINECT_HZ < 1.0
    at_true_lag = interpolate(moved.t, moved.positions, kinect.t + _lag(seed))
    oracle = register(at_true_lag, measured(kinect), joints)
    assert rotation_deg(pair.alignment.R @ oracle.R.T) < 1.0
    np.testing.assert_allclose(pair.alignment.t, oracle.t, atol=0.02)


@pytest.mark.parametrize("seed", [0, 1])
def test_refuses_a_pair_of_different_motions(seed: int) -> None:
    kinect, _, _ = simulated_pair(seed, 0.2, reps=5)
    _, other, _ = simulated_pair(seed + 10, 0.2, exercise="shoulder_abduction", reps=5)
    with pytest.raises(PairRefused) as info:
        align_pair(PairSpec(Path("k"), Path("m")), kinect, other, np.ones(skeleton.J, bool))
    assert info.value.reasons and "k: refused" in str(info.value)


def test_every_pair_refused_exits_non_zero(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    kinect, _, _ = simulated_pair(0, 0.2, reps=4)
    _, other, _ = simulated_pair(10, 0.2, exercise="shoulder_abduction", reps=4)
    k, m = write_pair(tmp_path, "bad", kinect, other)
    rc = main(["evaluate", "--kinect", str(k), "--mocap", str(m), "--out", str(tmp_path / "out"), "--no-figures"])
    assert rc == 1
    assert "every pair was refused" in capsys.readouterr().err
    summary = json.loads((tmp_path / "out" / "summary.json").read_text(encoding="utf-8"))
    assert [r["name"] for r in summary["refused"]] == ["bad_kinect"]


def test_a_partial_report_lists_the_refused_pair(tmp_path: Path) -> None:
    good_k, good_m, _ = simulated_pair(1, 0.4, reps=4)
    _, other, _ = simulated_pair(11, 0.2, exercise="shoulder_abduction", reps=4)
    k1, m1 = write_pair(tmp_path, "good", good_k, good_m)
    k2, m2 = write_pair(tmp_path, "bad", good_k, other)
    out = tmp_path / "out"
    rc = main(["evaluate", "--kinect", str(k1), "--mocap", str(m1), "--kinect", str(k2), "--mocap", str(m2),
               "--out", str(out), "--no-registration", "--no-figures"])  # fmt: skip
    assert rc == 0
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert [p["name"] for p in summary["pairs"]] == ["good_kinect"]
    assert [r["name"] for r in summary["refused"]] == ["bad_kinect"]
    assert "## Refused pairs" in (out / "report.md").read_text(encoding="utf-8")


def test_bad_input_names_the_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "broken_kinect.csv"
    bad.write_text("time,ROOT_x\n0.0,abc\n", encoding="utf-8")
    mocap = tmp_path / "broken_mocap.csv"
    mocap.write_text("nothing here", encoding="utf-8")
    rc = main(["evaluate", "--kinect", str(bad), "--mocap", str(mocap), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 2
    assert "broken_kinect.csv" in err


def test_unpaired_arguments_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc = main(["evaluate", "--kinect", "a.csv", "--out", str(tmp_path)])
    assert rc == 2
    assert "--kinect and --mocap must come in pairs" in capsys.readouterr().err


def test_missing_matplotlib_is_a_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(figures.PlottingUnavailable, match=r"kinect-home-coach\[evaluate\]"):
        figures.pyplot()


def test_without_matplotlib_the_command_stops_before_the_work(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    kinect, mocap, _ = simulated_pair(2, 0.3, reps=3)
    k, m = write_pair(tmp_path, "p", kinect, mocap)
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    rc = main(["evaluate", "--kinect", str(k), "--mocap", str(m), "--out", str(tmp_path / "out")])
    assert rc == 2
    assert "--no-figures" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
