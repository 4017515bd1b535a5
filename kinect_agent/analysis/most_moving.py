"""Most-moving joints: the joints ranked by the length of the path they travel during the session.

Definition. Positions (T, J, 3) metres in the camera frame are gap-filled and smoothed (series.smooth_positions:
Gaussian of SD 0.1 s, so that sensor jitter does not add path); a joint's path length is the sum over
consecutive frames of the distance it moves, in metres. Joints never tracked are left out. The list is sorted
by path length, longest first (ties keep skeleton order).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from kinect_agent.analysis import series
from kinect_agent.skeleton import JOINTS


def path_lengths(smoothed: np.ndarray) -> np.ndarray:
    """Returns (J,) metres travelled by each joint of smoothed positions (T, J, 3) m; NaN for untracked joints."""
    if smoothed.shape[0] < 2:
        return np.zeros(smoothed.shape[1])
    steps = series.norm3(np.diff(smoothed, axis=0))  # (T-1, J)
    return steps.sum(axis=0)


def most_moving_joints(smoothed: np.ndarray) -> list[dict[str, Any]]:
    """Returns [{"joint", "path_m"}] for every tracked joint, longest path first.

    smoothed: (T, J, 3) float, metres, camera frame, gap-filled and smoothed (series.smooth_positions).
    """
    lengths = path_lengths(smoothed)
    order = np.argsort(-np.nan_to_num(lengths, nan=-1.0), kind="stable")
    return [{"joint": JOINTS[j], "path_m": round(float(lengths[j]), 3)} for j in order if np.isfinite(lengths[j])]
