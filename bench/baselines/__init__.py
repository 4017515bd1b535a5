"""Reference smoothers the pipeline is compared against in bench/accuracy.py, one small module each.

Every baseline takes t: (T,) s and positions: (T, J, 3) float, metres, camera frame, NaN = untracked, and returns
filtered positions of the same shape (NaN only where the method has no estimate, e.g. before a causal filter's
first sample of a joint).
"""

from bench.baselines.butterworth import butterworth
from bench.baselines.cv_kalman import cv_kalman_rts
from bench.baselines.holt import holt_kinect
from bench.baselines.one_euro import one_euro

__all__ = ["butterworth", "cv_kalman_rts", "holt_kinect", "one_euro"]
