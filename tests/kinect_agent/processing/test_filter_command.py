"""`kinect-agent filter`: files in, filtered CSV and parameters JSON out, atomic, clear errors."""

from __future__ import annotations

import gc
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from kinect_agent import formats, skeleton
from kinect_agent.cli import main
from kinect_agent.commands import filter as filter_command
from kinect_agent.processing import pipeline
from kinect_agent.processing.params import KinematicParams
from kinect_agent.recording import Metadata, Recording

from ._data import smooth_motion


def _write_input(tmp_path: Path, rng: np.random.Generator, frames: int = 90) -> tuple[Path, Recording]:
    t, truth, _ = smooth_motion(frames, rng)
    positions = truth + rng.normal(0, 0.01, truth.shape)
    positions[30:35] = np.nan
    rec = Recording.from_positions(t + 12.5, positions, Metadata(rate_hz=30.0, device="kinect2"))
    path = tmp_path / "in.csv"
    formats.write(rec, path)
    return path, formats.read(path)


def test_filter_writes_complete_csv_and_params(tmp_path: Path, rng: np.random.Generator, capsys) -> None:
    src, rec = _write_input(tmp_path, rng)
    out, params = tmp_path / "out" / "filtered.csv", tmp_path / "params.json"
    assert main(["filter", str(src), "-o", str(out), "--params", str(params)]) == 0
    got = formats.read(out)
    np.testing.assert_allclose(got.t, rec.t, atol=1e-6, err_msg="frames and times are kept")
    assert np.all(np.isfinite(got.positions)) and np.all(got.state[30:35] == skeleton.INFERRED)
    doc = json.loads(params.read_text())
    p = KinematicParams.from_json(doc)
    assert p.n_frames == rec.n_frames
    np.testing.assert_allclose(p.positions(), got.positions, atol=2e-4)
    quality = doc["quality"]
    assert set(quality["outlier_fraction"]) == set(skeleton.JOINTS)
    before = np.mean(list(quality["segment_sd_before_mm"].values()))
    after = np.mean(list(quality["segment_sd_after_mm"].values()))
    assert before > 5.0 and after < 0.01, "the summary reports the noisy lengths going in and constant ones out"
    err = capsys.readouterr().err
    assert "frames" in err and f"segment-length SD {before:.1f} mm -> {after:.1f} mm" in err


def test_filter_without_params_writes_the_same_file_and_runs_without_the_cycle_collector(
    tmp_path: Path, rng: np.random.Generator, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Without --params the command skips the parameters and angle SDs (pipeline.filter_recording): the CSV is
    byte for byte the one written with --params; the cyclic garbage collector is off while it filters, on after."""
    src, _ = _write_input(tmp_path, rng)
    with_params, without = tmp_path / "with.csv", tmp_path / "without.csv"
    assert main(["filter", str(src), "-o", str(with_params), "--params", str(tmp_path / "p.json")]) == 0
    seen: list[bool] = []
    real = pipeline.filter_recording

    def spy(*args: Any, **kwargs: Any) -> pipeline.FilterResult:
        seen.append(gc.isenabled())
        return real(*args, **kwargs)

    monkeypatch.setattr(filter_command, "filter_recording", spy)
    assert gc.isenabled()
    assert main(["filter", str(src), "-o", str(without), "--no-progress"]) == 0
    assert seen == [False] and gc.isenabled()
    assert without.read_bytes() == with_params.read_bytes()


def test_the_program_freezes_its_objects_at_exit_and_a_caller_of_main_keeps_its_collector(
    tmp_path: Path, rng: np.random.Generator, monkeypatch: pytest.MonkeyPatch
) -> None:
    """`kinect-agent` (main() reading sys.argv) freezes what is left for the exit; main(argv) from Python does not."""
    src, _ = _write_input(tmp_path, rng, 40)
    frozen: list[bool] = []
    monkeypatch.setattr(gc, "freeze", lambda: frozen.append(True))
    assert main(["filter", str(src), "-o", str(tmp_path / "a.csv"), "--no-progress"]) == 0
    assert frozen == []
    monkeypatch.setattr(sys, "argv", ["kinect-agent", "filter", str(src), "-o", str(tmp_path / "b.csv")])
    assert main() == 0
    assert frozen == [True]


def test_filter_online_mode(tmp_path: Path, rng: np.random.Generator) -> None:
    src, rec = _write_input(tmp_path, rng, 60)
    out = tmp_path / "online.csv"
    assert main(["filter", str(src), "-o", str(out), "--online", "--no-progress"]) == 0
    assert "online forward pass" in formats.read(out).meta.history[-1]


def test_filter_error_leaves_no_output(tmp_path: Path, capsys) -> None:
    src = tmp_path / "empty.csv"
    rec = Recording.from_positions(np.arange(4.0), np.full((4, skeleton.J, 3), np.nan))
    formats.write(rec, src)
    out, params = tmp_path / "out.csv", tmp_path / "p.json"
    assert main(["filter", str(src), "-o", str(out), "--params", str(params)]) == 2
    assert "no joint is tracked" in capsys.readouterr().err
    assert not out.exists() and not params.exists()
    assert not list(tmp_path.glob(".*part")), "no temporary file left behind"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["missing.csv", "-o", "x.csv"], "no such file"),
        (["in.csv", "-o", "x.json"], "use a .csv name"),
    ],
)
def test_filter_bad_arguments_say_what_is_wrong(
    tmp_path: Path, rng: np.random.Generator, capsys, args: list[str], message: str
) -> None:
    _write_input(tmp_path, rng, 20)
    args = [str(tmp_path / a) if a.endswith((".csv", ".json")) else a for a in args]
    assert main(["filter", *args]) == 2
    assert message in capsys.readouterr().err


def test_no_progress_bar_when_stderr_is_a_log_file(tmp_path: Path, rng: np.random.Generator, capsys) -> None:
    src, _ = _write_input(tmp_path, rng, 1200)  # long enough for a bar on a terminal
    assert main(["filter", str(src), "-o", str(tmp_path / "f.csv")]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 2 and "\r" not in err and "step/s" not in err, err  # the summary lines only


def test_params_may_not_overwrite_the_metadata_sidecar(tmp_path: Path, rng: np.random.Generator, capsys) -> None:
    src, _ = _write_input(tmp_path, rng)
    out = tmp_path / "f.csv"
    assert main(["filter", str(src), "-o", str(out), "--params", str(tmp_path / "f.meta.json")]) == 2
    assert "must differ from the output file and its metadata sidecar" in capsys.readouterr().err
    assert not out.exists()
