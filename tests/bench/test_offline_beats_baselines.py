"""The offline pipeline against bench/accuracy.py's strongest baseline on simulated Kinect 1 data at 60°."""

import numpy as np
import pytest

from bench.baselines import cv_kalman_rts
from bench.baselines._common import hold_last
from kinect_agent.processing.pipeline import process
from kinect_agent.sources.simulator import simulate


@pytest.mark.parametrize("seed", [7, 8, 9])  # never one seed: a gain that holds on one draw only is no gain
def test_offline_is_closer_to_the_truth_than_cv_kalman_rts_at_kinect1_60(seed: int) -> None:
    """Kinect 1 at 60° (the noisiest setting: slow jitter, bias, tracking-loss bursts): the offline pipeline must beat
    the constant-velocity Kalman + RTS smoother. With the old sigma_tracked_m (15 mm) it did not here
    (133.6 vs 133.1 mm; now 127.6 mm; bench/README.md)."""
    measured, truth, _ = simulate("shoulder_abduction", 3, device="kinect1", view_deg=60, seed=seed)

    def rmse(est: np.ndarray) -> float:
        return float(np.sqrt(np.mean(np.sum((est - truth.positions) ** 2, axis=-1))))

    offline = rmse(process(measured).filtered.positions)
    baseline = rmse(hold_last(cv_kalman_rts(measured.t, measured.positions)))
    assert offline < baseline, f"offline {offline * 1e3:.1f} mm vs CV Kalman + RTS {baseline * 1e3:.1f} mm"
