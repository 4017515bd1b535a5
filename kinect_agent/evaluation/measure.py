"""Per-pair errors of the Kinect against the aligned mocap, at three stages:
    raw       the Kinect joints as recorded, TRACKED joint-frames only (state 2)
    clean     raw without the outliers of the paper's mixture (section 3.2): per joint, the Gaussian + uniform mixture
              (kinect_agent.processing.outliers.fit_mixture) fitted to the 3-D offsets against mocap, with the
              pipeline's floors (sigma >= outlier_min_sigma_m, uniform box >= outlier_min_range_m, rho >= 0.5);
              joint-frames with posterior(uniform) > 0.5 removed
    pipeline  the full pipeline's output (kinect_agent.processing.pipeline.process, offline), every overlap frame
Also the joint-frames the pipeline itself flags (outlier_prob > outlier_threshold), for its own removal gain.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinect_agent import skeleton
from kinect_agent.evaluation.pairs import Pair
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.outliers import MixtureFit, fit_mixture
from kinect_agent.processing.pipeline import process
from kinect_agent.skeleton import NOT_TRACKED, TRACKED

STAGES = ("raw", "clean", "pipeline")


@dataclass(frozen=True)
class PairErrors:
    """One pair's errors on its overlap frames T'. estimates: {stage: (T', J, 3) m, NaN = not counted}; truth:
    (T', J, 3) m, Kinect camera frame, NaN at unscored joints; mocap: (T', J, 3) m, the same with every mocap joint
    (its trunk gives the body frame of the error parts); t: (T',) s; pipeline_flags: (T', J) bool;
    mixture: the clean stage's fit (K = J columns, D = 3)."""

    pair: Pair
    t: np.ndarray
    truth: np.ndarray
    mocap: np.ndarray
    estimates: dict[str, np.ndarray]
    pipeline_flags: np.ndarray
    mixture: MixtureFit

    def distance(self, stage: str) -> np.ndarray:
        """Returns (T', J) m: the offset distance |estimate - mocap|, NaN where not counted."""
        return np.linalg.norm(self.estimates[stage] - self.truth, axis=-1)

    def segment_error(self, stage: str) -> np.ndarray:
        """Returns (T', 14) m: estimate minus mocap segment length (SEGMENT_NAMES order), NaN where not counted."""
        return skeleton.segment_lengths(self.estimates[stage]) - skeleton.segment_lengths(self.truth)


def mixture_outliers(err: np.ndarray, config: PipelineConfig) -> tuple[MixtureFit, np.ndarray]:
    """Returns (fit, outliers (T, J) bool) of the paper's mixture fitted per joint to err (T, J, 3) m (NaN = absent)."""
    mix = fit_mixture(err, min_sigma=config.outlier_min_sigma_m, min_width=config.outlier_min_range_m, min_rho=0.5)
    return mix, np.nan_to_num(mix.posterior_uniform(err), nan=0.0) > 0.5


def measure(pair: Pair, config: PipelineConfig | None = None) -> PairErrors:
    """Returns the pair's errors at every stage (module docstring)."""
    config = config or PipelineConfig()
    k, ov = pair.kinect, pair.overlap
    truth = np.where(pair.joints[None, :, None], pair.truth, np.nan)[ov]
    raw = np.where((k.state == TRACKED)[..., None], k.positions, np.nan)[ov]
    mix, outliers = mixture_outliers(raw - truth, config)
    res = process(k, config=config)
    prob = res.params.outlier_prob
    if prob is None:  # process() always sets it
        raise ValueError("the pipeline's result carries no outlier probabilities")
    flags = (prob > config.outlier_threshold) & (k.state != NOT_TRACKED)
    estimates = {
        "raw": raw,
        "clean": np.where(outliers[..., None], np.nan, raw),
        "pipeline": res.filtered.positions[ov],
    }
    return PairErrors(pair, k.t[ov], truth, pair.truth[ov], estimates, flags[ov], mix)
