"""Benchmark: the 3D replay recording of a session — time to build it and its size per minute of session.

Builds the replay of simulated squat sessions (raw + filtered, 30 Hz) of 1 and 10 minutes the way the server does
on first opening (backend.replay.scene.build on the decoded session file), several runs each; prints the median
build time, the recording size and its size per minute. Usage: python bench/replay.py [--runs 3] [--minutes 1 10]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from backend.replay import scene  # noqa: E402
from bench.sessions import squat_session  # noqa: E402
from kinect_agent.formats.session_file import SessionPayload, decode, encode  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402


def session_file(minutes: float) -> bytes:
    """Returns the .khs bytes of a simulated squat session of `minutes` minutes, filtered by the agent."""
    raw = squat_session(minutes)
    return encode(SessionPayload(session_id=f"bench-{minutes}", raw=raw, filtered=process(raw).filtered))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--minutes", type=float, nargs="+", default=[1.0, 10.0])
    args = parser.parse_args(argv)
    print(f"{'minutes':>8} {'frames':>7} {'build s (median)':>17} {'runs':>22} {'size MB':>8} {'MB/min':>7}")
    for minutes in args.minutes:
        data = session_file(minutes)
        times, size, frames = [], 0, 0
        for _ in range(args.runs):
            start = time.perf_counter()
            replay = scene.build(decode(data), "sagittal")
            times.append(time.perf_counter() - start)
            size, frames = len(replay.data), replay.n_frames
        runs = " ".join(f"{t:.2f}" for t in times)
        print(f"{minutes:8.1f} {frames:7d} {statistics.median(times):17.2f} {runs:>22} {size / 1e6:8.2f} "
              f"{size / 1e6 / minutes:7.2f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
