"""OpenSim marker files: a strict parser of the TRC layout, and OpenSim's own reader where the package installs."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from typing import Any

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.export import trc
from kinect_agent.sources.simulator import simulate


def parse_trc(text: str) -> tuple[dict[str, str], list[str], np.ndarray, np.ndarray]:
    """Returns (header values, marker names, times (T,), markers (T, M, 3) mm, NaN = empty) after checking every
    line of the layout; AssertionError names the first deviation."""
    lines = text.split("\n")
    first = lines[0].split("\t")
    assert first[:3] == ["PathFileType", "4", "(X/Y/Z)"], first
    keys, values = lines[1].split("\t"), lines[2].split("\t")
    assert keys == ["DataRate", "CameraRate", "NumFrames", "NumMarkers", "Units", "OrigDataRate",
                    "OrigDataStartFrame", "OrigNumFrames"], keys  # fmt: skip
    header = dict(zip(keys, values, strict=True))
    n_frames, n_markers = int(header["NumFrames"]), int(header["NumMarkers"])
    names_row = lines[3].split("\t")
    assert names_row[:2] == ["Frame#", "Time"]
    names = names_row[2::3]
    assert len(names) == n_markers and all(names_row[3 + 3 * k : 5 + 3 * k] == ["", ""] for k in range(n_markers - 1))
    axes = lines[4].split("\t")
    assert axes[:2] == ["", ""] and axes[2:] == [f"{a}{k}" for k in range(1, n_markers + 1) for a in "XYZ"]
    assert lines[5] == "", "a blank line separates the header from the data"
    rows = [line.split("\t") for line in lines[6:] if line]
    assert len(rows) == n_frames and lines[-1] == ""
    assert [int(r[0]) for r in rows] == list(range(1, n_frames + 1))
    assert all(len(r) == 2 + 3 * n_markers for r in rows)
    t = np.array([float(r[1]) for r in rows])
    xyz = np.array([[float(v) if v else np.nan for v in r[2:]] for r in rows]).reshape(n_frames, n_markers, 3)
    return header, names, t, xyz


@pytest.mark.parametrize(("exercise", "seed"), [("squat", 0), ("elbow_flexion", 1), ("side_step", 2)])
def test_trc_holds_every_joint_in_mm_with_the_recordings_times(exercise, seed):
    measured, _, _ = simulate(exercise, 2, seed=seed)
    header, names, t, xyz = parse_trc(trc.write_text(measured.t, measured.positions))
    assert names == list(skeleton.JOINTS)
    assert header["Units"] == "mm" and float(header["DataRate"]) == pytest.approx(measured.rate_hz, rel=1e-3)
    np.testing.assert_allclose(t, measured.t - measured.t[0], atol=1e-6)
    tracked = np.isfinite(measured.positions)
    np.testing.assert_array_equal(np.isfinite(xyz), tracked, err_msg="untracked joints are empty cells")
    np.testing.assert_allclose(xyz[tracked], measured.positions[tracked] * 1000, atol=5e-4)


def test_a_bad_shape_is_refused():
    _, truth, _ = simulate("squat", 1, seed=3)
    with pytest.raises(ValueError, match=r"positions must have shape \("):
        trc.write_text(truth.t, truth.positions[:, :10])


_OPENSIM_READ = """
import json, sys
import opensim
table = opensim.TimeSeriesTableVec3(sys.argv[1])
columns = [[[table.getDependentColumnAtIndex(j)[i].get(k) for k in range(3)] for i in range(table.getNumRows())]
           for j in range(table.getNumColumns())]
print(json.dumps({"labels": list(table.getColumnLabels()), "units": table.getTableMetaDataAsString("Units"),
                  "times": list(table.getIndependentColumn()), "columns": columns}).replace("NaN", "null"))
"""
needs_opensim = pytest.mark.skipif(
    importlib.util.find_spec("opensim") is None, reason="opensim has no wheel for this platform"
)


def opensim_read(path) -> dict[str, Any]:
    """Returns what OpenSim's TRC reader makes of `path`: labels, units, times (T,), columns (M, T, 3) mm, NaN =
    missing. OpenSim runs in a child process: its bundled BLAS would otherwise join this process's thread pools."""
    done = subprocess.run([sys.executable, "-c", _OPENSIM_READ, str(path)], capture_output=True, text=True, check=True)
    out = json.loads(done.stdout)
    out["times"] = np.array(out["times"])
    out["columns"] = np.array(out["columns"], dtype=float)
    return out


@needs_opensim
@pytest.mark.parametrize("seed", [4, 5])
def test_opensim_reads_the_markers(tmp_path, seed):
    _, truth, _ = simulate("squat", 2, seed=seed)
    path = tmp_path / "markers.trc"
    path.write_text(trc.write_text(truth.t, truth.positions, file_name=path.name), encoding="utf-8")
    table = opensim_read(path)
    assert table["labels"] == list(skeleton.JOINTS) and table["units"] == "mm"
    np.testing.assert_allclose(table["times"], truth.t - truth.t[0], atol=1e-6)
    np.testing.assert_allclose(table["columns"], truth.positions.transpose(1, 0, 2) * 1000, atol=5e-4)


@needs_opensim
@pytest.mark.parametrize("seed", [6, 7])
def test_opensim_reads_untracked_samples_as_missing(tmp_path, seed):
    _, truth, _ = simulate("squat", 1, seed=seed)
    positions = truth.positions.copy()
    head = skeleton.INDEX["HEAD"]
    positions[5:9, head] = np.nan
    path = tmp_path / "gaps.trc"
    path.write_text(trc.write_text(truth.t, positions), encoding="utf-8")
    missing = np.flatnonzero(np.isnan(opensim_read(path)["columns"][head, :, 0]))
    assert missing.tolist() == [5, 6, 7, 8]
