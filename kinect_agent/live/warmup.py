"""Readies the live loop before the patient's first set: the online filter's numba kernels are compiled (first run
after an install: about half a minute) or loaded from numba's on-disk cache (later runs: about a second), and SciPy's
lazily imported parts are loaded, so that the first set's first count comes as fast as any later set's.

`kinect-agent serve` calls warm_up() in a background thread at start-up; `kinect-agent pair` and `kinect-agent prepare`
call prepare(), which fills numba's on-disk cache for the live loop and the offline filter, so that serve's warm-up
only loads it (bench/first_count.py measures both).

Where the cache is, for the user who runs the command: $NUMBA_CACHE_DIR when set, else `__pycache__` beside the
installed modules when that user can write there (a venv the user made), else that user's cache folder
(`~/.cache/numba` on Linux, `%LOCALAPPDATA%\\numba\\numba\\Cache` on Windows), as numba chooses; when none of those
is writable (a read-only install run by a user without a home folder), $KINECT_AGENT_HOME/numba or a temporary folder
(kinect_agent.numba_cache). prepare() and serve's warm-up name the folder.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from kinect_agent.analysis.live import LiveCount
from kinect_agent.body.rotations import COMPILED_MIN_MATRICES, matrix_to_quat
from kinect_agent.formats import _csv_numba
from kinect_agent.numba_cache import ENV_HOME, TEMPORARY_PREFIX
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
    use) over 2 s of a simulated squat, and the compiled matrix_to_quat and Skeleton CSV rows that longer recordings
    reach; returns the seconds it took (first run after an install: about 15 s)."""
    started = time.perf_counter()
    rec = simulate(WARMUP_EXERCISE, 1, seed=0)[0]
    process(rec.slice(0, min(rec.n_frames, 60)))
    matrix_to_quat(np.broadcast_to(np.eye(3), (COMPILED_MIN_MATRICES, 3, 3)))
    if _csv_numba.AVAILABLE:
        _csv_numba.rows_text(np.zeros((1, 2)), np.array([5, 0]))
    return time.perf_counter() - started


def cache_folders() -> list[str]:
    """Returns the folders numba's on-disk cache of the agent's loaded kernels is in (sorted; empty without numba)."""
    return sorted({stats.cache_path for stats in _kernel_stats() if stats.cache_path})


def _kernel_stats() -> list[Any]:
    """Returns the compile statistics (numba's dispatcher stats: cache_path, cache_hits, cache_misses by signature)
    of every numba kernel the loaded kinect_agent modules define."""
    try:
        from numba.core.registry import CPUDispatcher
    except ImportError:  # the server's install: no numba, nothing to cache
        return []
    kernels = {id(obj): obj for name, module in list(sys.modules.items()) if name.startswith("kinect_agent")
               for obj in vars(module).values() if isinstance(obj, CPUDispatcher)}  # fmt: skip
    return [kernel.stats for kernel in kernels.values()]


def kernel_counts() -> dict[str, int]:
    """Returns how many of the loaded kernels' signatures numba loaded from its on-disk cache ("cache_hits") and how
    many it compiled ("cache_misses") in this process so far."""
    stats = _kernel_stats()
    return {"cache_hits": sum(sum(s.cache_hits.values()) for s in stats),
            "cache_misses": sum(sum(s.cache_misses.values()) for s in stats)}  # fmt: skip


def prepare() -> str:
    """Readies the live loop and the offline filter (warm_up, warm_up_offline), which fills numba's on-disk cache
    the first time; returns one line for the user: the seconds each took, how many kernels were compiled or loaded,
    and the cache's folder."""
    live_s, offline_s = warm_up(), warm_up_offline()
    counts, folders = kernel_counts(), cache_folders()
    return (f"filter ready: live {live_s:.1f} s, offline {offline_s:.1f} s; {counts['cache_misses']} kernels compiled, "
            f"{counts['cache_hits']} loaded from numba's cache in {where_cached(folders)}")  # fmt: skip


def where_cached(folders: list[str]) -> str:
    """Returns the cache folders (cache_folders()) for the user, with what to do when they are temporary (emptied when
    the computer restarts: the first set after it compiles again)."""
    if not folders:
        return "no cache (numba is not installed, or no folder is writable)"
    temporary = str(Path(tempfile.gettempdir()) / TEMPORARY_PREFIX)
    if any(folder.startswith(temporary) for folder in folders):
        return (f"{', '.join(folders)}, a temporary folder (the install and the home folder are not writable): set "
                f"{ENV_HOME} or NUMBA_CACHE_DIR to a folder this user keeps")  # fmt: skip
    return ", ".join(folders)


if __name__ == "__main__":  # at install (scripts/_venv.sh): numba's on-disk cache is filled before the first start
    print(prepare())
