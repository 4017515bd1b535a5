"""Data quality of one session as a 0-100 score with its parts, and the outlier timeline (a heat strip).

Parts, each scored 0-100 by a linear ramp between a "good" and a "bad" value, and weighted (weights sum to 1):
    tracked_fraction  fraction of (frame, joint) samples of the exercise's joints (quality.angle_joints) present
                      in the raw recording (state 1 or 2); 100 at ≥ 0.98, 0 at ≤ 0.60; weight 0.4;
    outlier_fraction  fraction of those present samples whose outlier probability exceeds the pipeline's
                      threshold (PipelineConfig.outlier_threshold, 0.95); 100 at ≤ 0.01, 0 at ≥ 0.15; weight 0.3;
    segment_spread_mm the median, over the 14 measured segments (skeleton.SEGMENTS) with at least MIN_SEGMENT_FRAMES
                      frames, of the robust spread of the segment's length in the raw recording before filtering:
                      1.4826 × median absolute deviation, millimetres (a rigid bone measured perfectly has 0);
                      100 at ≤ 10 mm, 0 at ≥ 50 mm; weight 0.3.
score = Σ weight × part score, rounded; LOW_SCORE (70) and below is low (the page then gives camera advice).

The outlier probabilities come from the agent's outlier model on the raw recording
(kinect_agent.processing.combined_outliers: the temporal Gaussian + uniform mixture of Wang et al., section 3.2,
plus sustained excursions), with the server's own settings (work_budget.SERVER_PIPELINE), never a file's.
The heat strip max-pools them over time into at most MAX_COLUMNS columns per joint; untracked samples carry no
probability (null), so a column where the joint was never seen is null.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from backend.i18n import N_, Translator
from kinect_agent.analysis.quality import angle_joints
from kinect_agent.processing.combined_outliers import outlier_probabilities_combined
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.recording import Recording
from kinect_agent.skeleton import JOINTS, NOT_TRACKED, SEGMENT_NAMES, segment_lengths

MAX_COLUMNS = 400
MIN_SEGMENT_FRAMES = 10
LOW_SCORE = 70
MAD_TO_SD = 1.4826
# part -> (good value, bad value, weight, label in English: the therapist catalogue's msgid, see part_label)
PARTS = {
    "tracked_fraction": (0.98, 0.60, 0.4, N_("Body seen by the camera")),
    "outlier_fraction": (0.01, 0.15, 0.3, N_("Tracking errors")),
    "segment_spread_mm": (10.0, 50.0, 0.3, N_("Steadiness of measured bone lengths")),
}


def part_label(name: str, t: Translator) -> str:
    """Returns the label of one part (PARTS) in t's language."""
    return t.gettext(PARTS[name][3])


def outlier_probabilities(raw: Recording, config: PipelineConfig | None = None) -> np.ndarray:
    """Returns (T, J) in [0, 1], the agent's outlier probability of each raw sample; NaN where untracked."""
    config = config or PipelineConfig()
    prob = outlier_probabilities_combined(raw, config)
    return np.where(raw.state == NOT_TRACKED, np.nan, prob)


def segment_spread_mm(positions: np.ndarray) -> dict[str, float | None]:
    """Returns {segment: robust spread of its length, mm} over frames where both ends are known (module doc).

    positions: (T, J, 3) m, any frame, NaN = untracked. None for a segment seen in fewer than MIN_SEGMENT_FRAMES
    frames.
    """
    lengths = segment_lengths(np.asarray(positions, dtype=np.float64))  # (T, 14) m
    out: dict[str, float | None] = {}
    for k, name in enumerate(SEGMENT_NAMES):
        x = lengths[:, k][np.isfinite(lengths[:, k])]
        if x.size < MIN_SEGMENT_FRAMES:
            out[name] = None
            continue
        out[name] = round(float(MAD_TO_SD * np.median(np.abs(x - np.median(x))) * 1000.0), 1)
    return out


def part_score(name: str, value: float | None) -> float | None:
    """Returns the 0-100 score of one part (PARTS) for its value by the linear ramp; None for an unknown value."""
    if value is None or not np.isfinite(value):
        return None
    good, bad, _, _ = PARTS[name]
    return float(np.clip(100.0 * (value - bad) / (good - bad), 0.0, 100.0))


def quality_score(values: dict[str, float | None]) -> tuple[int, list[dict[str, Any]]]:
    """Returns (score 0-100, parts [{"name", "label", "value", "score", "weight"}]) of part values.

    values: {part name: value} for the names of PARTS. A part with no value is left out and the other weights
    are renormalised; with no part at all the score is 0.
    """
    parts, total, weights = [], 0.0, 0.0
    for name, (_, _, weight, label) in PARTS.items():
        value = values.get(name)
        score = part_score(name, value)
        rounded = None if score is None else round(score)
        parts.append({"name": name, "label": label, "value": value, "score": rounded, "weight": weight})
        if score is not None:
            total += weight * score
            weights += weight
    return (int(round(total / weights)) if weights else 0), parts


def outlier_strip(t: np.ndarray, prob: np.ndarray, max_columns: int = MAX_COLUMNS) -> dict[str, Any]:
    """Returns {"joints", "t_s", "column_s", "prob"}: prob (T, J) max-pooled over time into ≤ max_columns columns.

    t: (T,) s. prob: (T, J) in [0, 1], NaN = no sample. "t_s": (C,) the time of each column's centre, seconds
    from t[0]; "column_s": the columns' common width in seconds; "prob": J rows of C values (2 decimals) or null.
    """
    t = np.asarray(t, dtype=np.float64)
    prob = np.asarray(prob, dtype=np.float64)
    T, J = prob.shape
    if t.shape != (T,):
        raise ValueError(f"t must have shape ({T},), got {t.shape}")
    size = max(1, -(-T // max_columns))
    n_cols = -(-T // size)
    padded = np.full((n_cols * size, J), np.nan)
    padded[:T] = prob
    cols = padded.reshape(n_cols, size, J)
    seen = np.isfinite(cols).any(axis=1)
    pooled = np.where(seen, np.where(np.isfinite(cols), cols, -1.0).max(axis=1), np.nan)  # (C, J)
    t_s = t - t[0]
    first = np.arange(n_cols) * size
    last = np.minimum(first + size - 1, T - 1)
    dt = float(np.median(np.diff(t))) if T > 1 else 0.0
    rows = [[None if not np.isfinite(v) else round(float(v), 2) for v in pooled[:, j]] for j in range(J)]
    return {
        "joints": list(JOINTS),
        "t_s": [round(float(v), 3) for v in 0.5 * (t_s[first] + t_s[last])],
        "column_s": round(size * dt, 3),
        "prob": rows,
    }


def assess(raw: Recording, prob: np.ndarray, angle_names: tuple[str, ...], threshold: float) -> dict[str, Any]:
    """Returns {"score", "low", "parts", "segment_spread_mm"} of a session (module doc).

    raw: the recording as captured. prob: (T, J) outlier probabilities of its samples (NaN where untracked).
    angle_names: the exercise's defining angles (their joints are scored; all joints when empty). threshold:
    the probability above which a sample is an outlier.
    """
    joints = angle_joints(angle_names)
    present = raw.state[:, joints] != NOT_TRACKED
    tracked = float(present.mean()) if present.size else None
    flagged = present & (np.nan_to_num(prob[:, joints], nan=0.0) > threshold)
    outliers = float(flagged.sum() / present.sum()) if present.any() else None
    spreads = segment_spread_mm(raw.positions)
    known = [v for v in spreads.values() if v is not None]
    spread = float(np.median(known)) if known else None
    values = {
        "tracked_fraction": None if tracked is None else round(tracked, 4),
        "outlier_fraction": None if outliers is None else round(outliers, 4),
        "segment_spread_mm": None if spread is None else round(spread, 1),
    }
    score, parts = quality_score(values)
    return {"score": score, "low": score <= LOW_SCORE, "parts": parts, "segment_spread_mm": spreads}
