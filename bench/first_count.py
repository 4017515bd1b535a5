"""How long the live loop takes to answer the first frames of a set after Start, first set against later ones.

The patient's first live set after an install showed its first count 5-11 s after Start and later sets about 1 s
(issue 26): the online filter's numba kernels compile on the first frame. Each scenario runs in a fresh process
with the environment as it is (nothing set for the product): numba keeps the compiled kernels in its on-disk cache
beside the product's modules (`cache=True`: __pycache__/*.nbi, *.nbc, or numba's user-wide cache where the install
is read-only). "Empty cache" = those files of kinect_agent removed first, as after a fresh install; the cold runs
write them again.

    cold        empty cache, no warm-up: the first set compiles
    cached      the cache filled by an earlier run, no warm-up: the first set loads the compiled code
    warmed      empty cache, kinect_agent.live.warmup.warm_up() done first, as `kinect-agent serve` does at start-up
    paired      empty cache, then `kinect-agent prepare` (what `kinect-agent pair` runs after pairing) in a process
                of its own; then the first set in a fresh process at once, no warm-up (Start the moment serve starts)
    paired+up   the same, with serve's warm-up (now a load from the cache) done before Start
    later set   the second set in the same process as "cold"

A "set" is OnlineFilter + LiveCount fed a simulated squat frame by frame as SetRecorder does (no waiting for the
camera's 30 Hz). Printed: Start -> first frame's status (what the first message to the page waits for), Start -> 30
frames done (one second of camera), the warm-up's own time with an empty and with a prepared cache, and
`kinect-agent prepare`'s. Median of --runs runs.

    .venv/bin/python bench/first_count.py --runs 3
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import TypedDict

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, sys, time
warm = sys.argv[1] == "1"
from kinect_agent.analysis.live import LiveCount
from kinect_agent.live.warmup import WARMUP_ANGLES, warm_up
from kinect_agent.processing.online import OnlineFilter
from kinect_agent.sources.simulator import simulate

def one_set(seed):
    rec = simulate("squat", 2, seed=seed)[0]
    start = time.perf_counter()
    online, counter = OnlineFilter(), LiveCount(WARMUP_ANGLES)
    first = None
    for k in range(30):
        t = float(rec.t[k])
        counter.add(t, rec.positions[k], rec.state[k], online.step(t, rec.positions[k], rec.state[k]))
        first = time.perf_counter() - start if first is None else first
    return first, time.perf_counter() - start

warm_s = warm_up() if warm else None
first = one_set(7)
later = one_set(8)
print(json.dumps({"warm_up_s": warm_s, "first": first, "later": later}))
"""


def empty_cache() -> int:
    """Removes numba's cached kernels of kinect_agent (index .nbi and data .nbc files); returns how many."""
    files = [p for pattern in ("*.nbi", "*.nbc") for p in (ROOT / "kinect_agent").rglob(f"__pycache__/{pattern}")]
    for path in files:
        path.unlink(missing_ok=True)
    return len(files)


class ChildRun(TypedDict):
    """What CHILD prints: seconds of the warm-up (None: not warmed up), and (Start -> first frame, Start -> 30
    frames) s of the first and of a later set."""

    warm_up_s: float | None
    first: list[float]
    later: list[float]


def run(warm: bool) -> ChildRun:
    """Runs CHILD in a fresh process (the environment as it is, the repository on the import path)."""
    done = subprocess.run([sys.executable, "-c", CHILD, "1" if warm else "0"], cwd=ROOT, capture_output=True,
                          text=True, check=True)  # fmt: skip
    return json.loads(done.stdout.strip().splitlines()[-1])


def prepare() -> float:
    """Runs `kinect-agent prepare` in a process of its own (the environment as it is); returns its wall seconds."""
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "kinect_agent.cli", "prepare"], cwd=ROOT, capture_output=True, check=True)
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    rows: dict[str, list[tuple[float, ...]]] = {
        "cold": [], "cached": [], "warmed": [], "paired": [], "paired+up": [], "later set": []}  # fmt: skip
    warm_ups: list[float] = []
    loads: list[float] = []
    prepares: list[float] = []
    for _ in range(args.runs):
        empty_cache()
        cold = run(warm=False)
        rows["cold"].append(tuple(cold["first"]))
        rows["later set"].append(tuple(cold["later"]))
        rows["cached"].append(tuple(run(warm=False)["first"]))
        empty_cache()
        warmed = run(warm=True)
        rows["warmed"].append(tuple(warmed["first"]))
        warm_up_s = warmed["warm_up_s"]
        if warm_up_s is None:
            raise RuntimeError("the warmed run reports no warm-up")
        warm_ups.append(warm_up_s)
        empty_cache()
        prepares.append(prepare())
        rows["paired"].append(tuple(run(warm=False)["first"]))
        paired_up = run(warm=True)
        rows["paired+up"].append(tuple(paired_up["first"]))
        loads.append(paired_up["warm_up_s"] or 0.0)
    print(f"{'scenario':<10} {'Start -> first frame':>22} {'Start -> 30 frames':>20}   (median of {args.runs})")
    for name, values in rows.items():
        first = statistics.median(v[0] for v in values)
        thirty = statistics.median(v[1] for v in values)
        print(f"{name:<10} {first * 1000:>19.0f} ms {thirty * 1000:>17.0f} ms")
    print(f"warm-up itself (empty cache, at serve's start-up): {statistics.median(warm_ups):.1f} s")
    print(f"warm-up itself (cache filled by prepare, at serve's start-up): {statistics.median(loads):.2f} s")
    print(f"kinect-agent prepare (empty cache, its own process): {statistics.median(prepares):.1f} s")


if __name__ == "__main__":
    main()
