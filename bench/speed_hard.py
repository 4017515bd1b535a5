"""Speed of filtering a 10-minute recording as a user runs it, clean and outlier-heavy (issue 24, point 5).

Writes two 10-minute 30 Hz Skeleton CSV files into a temporary folder (bench/sessions.py, deterministic seeds):
  clean  simulated Kinect 2 squats (the simulator's own 2-6 % tracking-loss bursts), as bench/speed.py times;
  hard   the same with tracking loss added until about 10 % of the joint-frames are lost or wild.
Then, per file, `kinect-agent filter FILE -o OUT.csv` in a fresh process (what the user waits for: start-up, reading,
pipeline, writing; the compiled kernels come from numba's disk cache, warmed once before timing), and in one
process the stages read / process / write with the pipeline's own split (outliers, passes, smoother), process being
pipeline.filter_recording as in the command.
Prints medians of --repeats runs, wall and CPU seconds (CPU time is the steadier figure on a shared machine).
    python bench/speed_hard.py [--repeats 5] [--minutes 10] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import TypedDict

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:  # `python bench/speed_hard.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT_DIR))

from bench.sessions import outlier_heavy_session, squat_session  # noqa: E402
from kinect_agent import formats  # noqa: E402
from kinect_agent.processing import pipeline  # noqa: E402
from kinect_agent.processing.config import PipelineConfig  # noqa: E402

TARGET_S = 5.0
_COMMAND = "import sys; from kinect_agent.cli import main; sys.exit(main())"  # as the kinect-agent script


def command_seconds(path: Path, out: Path) -> tuple[float, float]:
    """Returns (wall s, CPU s of the child) of `kinect-agent filter path -o out` in a fresh Python process."""
    args = [sys.executable, "-c", _COMMAND, "filter", str(path), "-o", str(out), "--no-progress"]
    start = time.perf_counter()
    done = subprocess.run(args, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"kinect-agent filter failed: {done.stderr}")
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, usage.ru_utime + usage.ru_stime


def stage_seconds(path: Path, out: Path) -> dict[str, float]:
    """Returns wall seconds of read, process and write in this process, and the CPU seconds of process and of its
    parts (the pipeline's own clock). "process" is pipeline.filter_recording, what the command runs without
    --params (process() adds the angle SDs, the smoothed covariances and the kinematic parameters)."""
    timings: dict[str, float] = {}
    start = time.perf_counter()
    rec = formats.read(path)
    timings["read"] = time.perf_counter() - start
    start, cpu = time.perf_counter(), time.process_time()
    result = pipeline.filter_recording(rec, config=PipelineConfig())
    timings["process"] = time.perf_counter() - start
    timings["process_cpu"] = time.process_time() - cpu
    timings.update({f"  {k} (CPU)": v for k, v in result.quality.get("stage_cpu_seconds", {}).items()})
    start = time.perf_counter()
    formats.write(result.filtered, out, "csv")
    timings["write"] = time.perf_counter() - start
    timings["n_outliers"] = result.quality["n_outliers"]
    return timings


class CommandTimes(TypedDict):
    """Medians of the filter command: wall s (and each run's), CPU s, and every stage's (stage_seconds)."""

    command_s: float
    command_runs_s: list[float]
    command_cpu_s: float
    stages: dict[str, float]


def measure(path: Path, work: Path, repeats: int) -> CommandTimes:
    """Returns the medians over `repeats` runs of the command (wall, CPU) and of every stage."""
    runs, cpus, stages = [], [], []
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    child_cpu = usage.ru_utime + usage.ru_stime
    for _ in range(repeats):
        wall, cpu_total = command_seconds(path, work / "out.csv")
        runs.append(wall)
        cpus.append(cpu_total - child_cpu)
        child_cpu = cpu_total
        stages.append(stage_seconds(path, work / "out_stages.csv"))
    med = {k: statistics.median(s[k] for s in stages) for k in stages[0]}
    return {"command_s": statistics.median(runs), "command_runs_s": runs, "command_cpu_s": statistics.median(cpus),
            "stages": med}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--json", help="also write the numbers to this file")
    args = parser.parse_args(argv)
    results: dict[str, CommandTimes] = {}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        files = {"clean": squat_session(args.minutes), "hard": outlier_heavy_session(args.minutes)}
        for name, rec in files.items():
            formats.write(rec, work / f"{name}.csv", "csv")
        command_seconds(work / "clean.csv", work / "warm.csv")  # numba's disk cache, page cache
        pipeline.process(squat_session(0.1))  # this process's kernels
        for name in files:
            r = measure(work / f"{name}.csv", work, args.repeats)
            results[name] = r
            measured = (("wall", r["command_s"]), ("CPU", r["command_cpu_s"]))
            verdict = ", ".join(f"{what} {'PASS' if seconds <= TARGET_S else 'FAIL'}" for what, seconds in measured)
            runs = ", ".join(f"{s:.2f}" for s in r["command_runs_s"])
            print(f"{name}: kinect-agent filter, {args.minutes:g} min: median {r['command_s']:.2f} s wall ({runs}), "
                  f"{r['command_cpu_s']:.2f} s CPU (target <= {TARGET_S:g} s: {verdict}); "
                  f"{int(r['stages']['n_outliers'])} outliers removed")  # fmt: skip
            for stage, sec in r["stages"].items():
                if stage != "n_outliers":
                    print(f"    {stage:18s} {sec:6.2f} s")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
