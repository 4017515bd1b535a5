"""Outlier removal from several kinds of evidence: the temporal mixture (outliers.py, always), the segment-length
mixture (segment_outliers.py, PipelineConfig.outlier_segment) and sustained excursions (excursions.py,
PipelineConfig.outlier_excursions). Excursions are on by default, the segment residual is off; each module's docstring
gives its measurements.
"""

from __future__ import annotations

import numpy as np

from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.excursions import excursion_probabilities
from kinect_agent.processing.outliers import drop_outliers, outlier_probabilities
from kinect_agent.processing.segment_outliers import segment_outlier_probabilities
from kinect_agent.recording import Recording


def combine(p_temporal: np.ndarray, p_other: np.ndarray, how: str = "or") -> np.ndarray:
    """Returns (T, J): two outlier probabilities combined, "or" = 1 − (1 − p_t)(1 − p_o) (independent evidence),
    "max", or "and" = min(p_t, p_o) (both must flag it)."""
    if how == "or":
        return 1.0 - (1.0 - p_temporal) * (1.0 - p_other)
    if how == "max":
        return np.maximum(p_temporal, p_other)
    if how == "and":
        return np.minimum(p_temporal, p_other)
    raise ValueError(f"how must be 'or', 'max' or 'and', got {how!r}")


def outlier_probabilities_combined(rec: Recording, config: PipelineConfig) -> np.ndarray:
    """Returns (T, J) in [0, 1]: the temporal probability, combined with the extra evidence the config turns on."""
    prob = outlier_probabilities(rec, config)
    if config.outlier_segment is not None:
        prob = combine(prob, segment_outlier_probabilities(rec, config), config.outlier_segment)
    if config.outlier_excursions:
        prob = np.maximum(prob, excursion_probabilities(rec, config))
    return prob


def remove_outliers_combined(rec: Recording, config: PipelineConfig | None = None) -> tuple[Recording, np.ndarray]:
    """Returns (recording with outliers set to NaN and state 0, prob (T, J)); the input is not changed."""
    config = config or PipelineConfig()
    prob = outlier_probabilities_combined(rec, config)
    extras = [f"segment length ({config.outlier_segment})"] if config.outlier_segment else []
    extras += ["excursions"] if config.outlier_excursions else []
    method = " + ".join(["mixture-model v1", *extras])
    return drop_outliers(rec, prob, config.outlier_threshold, method), prob
