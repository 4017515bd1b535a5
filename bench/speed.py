"""Speed of the signal pipeline: UKF step vs filterpy, whole pipeline on 10 minutes (clean and outlier-heavy),
online step p99.

The environment is left as the user's: the product limits BLAS to one thread itself (kinect_agent.blas_threads;
pipeline.process does, and the agent's command line does for the whole process, which this script does the same way
for the step timings). Prints the median of several repeats. --busy N runs N CPU-bound processes beside it, as on a
home computer or a server busy with other work.
    python bench/speed.py [--quick] [--busy N] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from filterpy.kalman import MerweScaledSigmaPoints as FMerwe
from filterpy.kalman import UnscentedKalmanFilter as FUKF

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:  # `python bench/speed.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT_DIR))

from bench.sessions import outlier_heavy_session, squat_session  # noqa: E402
from kinect_agent.blas_threads import one_blas_thread  # noqa: E402
from kinect_agent.processing import ik, pipeline  # noqa: E402
from kinect_agent.processing.chain_filter import ChainFilter  # noqa: E402
from kinect_agent.processing.config import PipelineConfig  # noqa: E402
from kinect_agent.processing.online import OnlineFilter  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402


@contextmanager
def busy_cores(n: int) -> Iterator[None]:
    """Runs n CPU-bound processes (a Python loop each) while the block runs; stops them after."""
    procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]
    try:
        time.sleep(0.5 if n else 0.0)  # let them take their cores
        yield
    finally:
        for proc in procs:
            proc.kill()
            proc.wait()


def _time_steps(step: Callable[[np.ndarray], object], z: np.ndarray, repeats: int) -> float:
    """Returns the median seconds per step of step(z_t) over all frames of z, over `repeats` runs."""
    for frame in z[:5]:  # warm up (compiled kernels, caches)
        step(frame)
    runs = []
    for _ in range(repeats):
        start = time.perf_counter()
        for frame in z:
            step(frame)
        runs.append((time.perf_counter() - start) / len(z))
    return statistics.median(runs)


def ukf_step_comparison(rec: Recording, frames: int, repeats: int) -> dict[str, float]:
    """Times one predict+update of this UKF and of filterpy's UKF with the same chain model and data."""
    fit = ik.inverse_kinematics(rec.positions)
    x0 = np.concatenate([fit.root[0], fit.theta[0]])
    n = x0.size
    z = np.nan_to_num(rec.positions[:frames].reshape(frames, -1), nan=0.0)
    Q, R = np.eye(n) * 1e-4, np.eye(60) * 0.015**2

    # This pipeline's step, as pipeline.process runs it: random walk (diagonal Q) then the gated update.
    ours = ChainFilter(fit.model, fit.lengths, PipelineConfig(), x0.copy())  # lengths fixed: passes 3-4's state
    ours.P, ours.Q = np.eye(n) * 0.01, Q
    observed, R_diag = np.ones(60, dtype=bool), R.diagonal()

    def our_step(frame: np.ndarray) -> None:
        ours.predict_random_walk(1.0)
        ours.update_joints(frame, observed, R_diag, None)

    points = FMerwe(n, alpha=0.5, beta=2.0, kappa=0.0)
    theirs = FUKF(dim_x=n, dim_z=60, dt=1 / 30, hx=lambda x: ours.hx(x[None, :])[0].copy(), fx=lambda x, dt: x,
                  points=points)  # fmt: skip
    theirs.x, theirs.P, theirs.Q, theirs.R = x0.copy(), np.eye(n) * 0.01, Q, R

    def their_step(frame: np.ndarray) -> None:
        theirs.predict()
        theirs.update(frame)

    t_ours = _time_steps(our_step, z, repeats)
    t_theirs = _time_steps(their_step, z, repeats)
    return {"state_dim": n, "ours_ms": t_ours * 1e3, "filterpy_ms": t_theirs * 1e3, "speedup": t_theirs / t_ours}


def whole_pipeline(rec: Recording, repeats: int) -> dict[str, float | list[float]]:
    """Times pipeline.process on the whole recording (offline, default smoother)."""
    runs = []
    for _ in range(repeats):
        start = time.perf_counter()
        pipeline.process(rec)
        runs.append(time.perf_counter() - start)
    return {"frames": rec.n_frames, "minutes": rec.duration / 60.0, "median_s": statistics.median(runs), "runs_s": runs}


def online_latency(rec: Recording) -> dict[str, float]:
    """Times every OnlineFilter.step after the first second; returns median and p99 in ms."""
    live = OnlineFilter()
    times = []
    for i in range(rec.n_frames):
        start = time.perf_counter()
        live.step(float(rec.t[i]), rec.positions[i], rec.state[i])
        times.append(time.perf_counter() - start)
    steady = np.array(times[int(rec.rate_hz * 2) :]) * 1e3
    return {"median_ms": float(np.median(steady)), "p99_ms": float(np.percentile(steady, 99))}


def main() -> None:
    """Runs the three measurements and prints them against the targets."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="short smoke run (not for reporting)")
    parser.add_argument("--json", help="also write the numbers to this file")
    parser.add_argument("--busy", type=int, default=0, help="CPU-bound processes running beside the measurements")
    args = parser.parse_args()
    minutes, repeats, frames = (0.5, 1, 60) if args.quick else (10.0, 3, 600)
    one_blas_thread()  # what the agent's command line does at start (kinect_agent.cli.main)
    pipeline.process(squat_session(0.1))  # compile the numba kernels before timing
    rec = squat_session(minutes)
    with busy_cores(args.busy):
        results = {
            "busy_processes": args.busy,
            "ukf_step": ukf_step_comparison(rec, frames, repeats),
            "pipeline": whole_pipeline(rec, repeats),
            "pipeline_hard": whole_pipeline(outlier_heavy_session(minutes), repeats),
            "online": online_latency(rec),
        }
    u, p, o = results["ukf_step"], results["pipeline"], results["online"]
    print(f"UKF step (n={u['state_dim']}): ours {u['ours_ms']:.3f} ms, filterpy {u['filterpy_ms']:.3f} ms, "
          f"speed-up {u['speedup']:.1f}x (target >= 20x: {'PASS' if u['speedup'] >= 20 else 'FAIL'})")  # fmt: skip
    print(f"whole pipeline, {p['frames']} frames ({p['minutes']:.1f} min): median {p['median_s']:.2f} s "
          f"(target <= 15 s for 10 min: {'PASS' if p['median_s'] <= 15 else 'FAIL'})")  # fmt: skip
    h = results["pipeline_hard"]
    print(f"whole pipeline, outlier-heavy (10 % lost or wild), {h['frames']} frames: median {h['median_s']:.2f} s "
          f"(target <= 5 s for 10 min: {'PASS' if h['median_s'] <= 5 else 'FAIL'})")  # fmt: skip
    print(f"online step: median {o['median_ms']:.3f} ms, p99 {o['p99_ms']:.3f} ms "
          f"(target p99 <= 2 ms: {'PASS' if o['p99_ms'] <= 2 else 'FAIL'})")  # fmt: skip
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=2)


if __name__ == "__main__":
    main()
