"""Internal faults of the processing (ProcessingError) are kept apart from bad input: the filter raises them, the
command line says "internal fault" with exit status 1 (bad input: "error", 2)."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

from kinect_agent import formats
from kinect_agent.cli import main
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.errors import FilterDiverged, NotPositiveDefinite, ProcessingError
from kinect_agent.processing.pipeline import process
from kinect_agent.recording import Metadata, Recording
from kinect_agent.sources.simulator import simulate

# Measurement SDs of 1e-160 m: R = 1e-320 m² underflows to a denormal and the innovation covariance of a converged
# filter loses positive definiteness. Valid settings (> 0) on which the filter fails: a fault of the filter.
DEGENERATE = {"sigma_tracked_m": 1e-160, "sigma_inferred_m": 1e-160}


@pytest.mark.parametrize("seed", [0, 1])
def test_a_degenerate_covariance_raises_a_processing_error(seed: int) -> None:
    rec = simulate("squat", 2, seed=seed)[0]
    with pytest.raises(NotPositiveDefinite, match="not positive definite") as caught:
        process(rec, config=PipelineConfig(**DEGENERATE))
    assert not isinstance(caught.value, ValueError), "an internal fault must not look like bad input"


def test_the_cli_reports_an_internal_fault_with_status_1(tmp_path: Path, monkeypatch, capsys) -> None:
    src, out = tmp_path / "in.csv", tmp_path / "out.csv"
    formats.write(simulate("squat", 2, seed=0)[0], src)
    monkeypatch.setattr("kinect_agent.commands.filter.PipelineConfig", functools.partial(PipelineConfig, **DEGENERATE))
    assert main(["filter", str(src), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "internal fault (NotPositiveDefinite)" in err and "The input was accepted" in err, err
    assert "error:" not in err, "an internal fault is not reported as the user's error"
    assert not out.exists()


def test_positions_not_in_metres_are_bad_input_with_status_2(tmp_path: Path, capsys) -> None:
    rec = simulate("squat", 2, seed=0)[0]
    src = tmp_path / "mm.csv"
    formats.write(Recording(rec.t, rec.positions * 1000.0, rec.state, Metadata(rate_hz=rec.meta.rate_hz)), src)
    assert main(["filter", str(src), "-o", str(tmp_path / "out.csv")]) == 2
    assert "must be in metres" in capsys.readouterr().err


def test_processing_errors_are_not_value_errors() -> None:
    assert issubclass(NotPositiveDefinite, ProcessingError)
    assert not issubclass(ProcessingError, ValueError)
    assert np.isfinite(PipelineConfig(**DEGENERATE).sigma_tracked_m), "the settings themselves are valid"


def diverging(smooth):
    """Returns pipeline.smooth whose joint angles are not finite in frames 10-12: a filter that diverged there."""

    def smooth_then_diverge(*args, **kwargs):
        root, lengths, theta, info = smooth(*args, **kwargs)
        theta = theta.copy()
        theta[10:13] = np.nan
        return root, lengths, theta, info

    return smooth_then_diverge


def test_a_diverged_filter_is_an_internal_fault_not_bad_input(tmp_path: Path, monkeypatch, capsys) -> None:
    from kinect_agent.processing import pipeline

    monkeypatch.setattr(pipeline, "smooth", diverging(pipeline.smooth))
    rec = simulate("squat", 2, seed=0)[0]
    with pytest.raises(FilterDiverged, match=r"not finite in 3 of \d+ frames \(first: frame 10\)"):
        process(rec)
    src, out = tmp_path / "in.csv", tmp_path / "out.csv"
    formats.write(rec, src)
    assert main(["filter", str(src), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "internal fault (FilterDiverged)" in err and "first: frame 10" in err, err
    assert "error:" not in err and not out.exists()
