"""Readies the live loop before the patient's first set: the online filter's numba kernels are compiled (first run
after an install: about half a minute) or loaded from numba's on-disk cache (later runs: about a second), and SciPy's
lazily imported parts are loaded, so that the first set's first count comes as fast as any later set's.

`kinect-agent serve` calls warm_up() in a background thread at start-up (bench/first_count.py measures the effect).
"""

from __future__ import annotations

import time

import numpy as np

from kinect_agent.analysis.live import LiveCount
from kinect_agent.body.rotations import COMPILED_MIN_MATRICES, matrix_to_quat
from kinect_agent.processing.online import OnlineFilter
from kinect_agent.processing.pipeline import process
from kinect_agent.sources.simulator import simulate

WARMUP_EXERCISE = "squat"
WARMUP_ANGLES = ("knee_flexion_L", "knee_flexion_R")
WARMUP_FRAMES = 90  # 3 s at 30 Hz: several of LiveCount's evaluations (every 0.25 s) and the filter's start


def warm_up() -> float:
    """Runs the live loop (OnlineFilter, then LiveCount, frame by frame as SetRecorder does) over the first 3 s of a
    simulated squat; returns the seconds it took."""
    started = time.perf_counter()
    rec = simulate(WARMUP_EXERCISE, 1, seed=0)[0]
    online, counter = OnlineFilter(), LiveCount(WARMUP_ANGLES)
    for k in range(min(rec.n_frames, WARMUP_FRAMES)):
        t = float(rec.t[k])
        counter.add(t, rec.positions[k], rec.state[k], online.step(t, rec.positions[k], rec.state[k]))
    counter.final()
    return time.perf_counter() - started


def warm_up_offline() -> float:
    """Runs the offline pipeline (outlier model and filter passes, whose compiled kernels the live loop does not
    use) over 2 s of a simulated squat, and the compiled matrix_to_quat that longer recordings reach; returns the
    seconds it took (first run after an install: about 15 s)."""
    started = time.perf_counter()
    rec = simulate(WARMUP_EXERCISE, 1, seed=0)[0]
    process(rec.slice(0, min(rec.n_frames, 60)))
    matrix_to_quat(np.broadcast_to(np.eye(3), (COMPILED_MIN_MATRICES, 3, 3)))
    return time.perf_counter() - started


if __name__ == "__main__":  # at install (scripts/_venv.sh): numba's on-disk cache is filled before the first start
    print(f"live filter compiled in {warm_up():.1f} s")
    print(f"offline filter compiled in {warm_up_offline():.1f} s")
