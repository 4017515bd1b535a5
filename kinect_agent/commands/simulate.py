"""`kinect-agent simulate`: a simulated exercise session, as the Kinect would measure it, plus the exact truth."""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path

from kinect_agent import formats
from kinect_agent.sources import kinect_noise
from kinect_agent.sources.simulator import EXERCISES, simulate

NAME = "simulate"
HELP = "Simulate an exercise session measured by a Kinect (errors calibrated on Wang et al.'s tables)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares the simulate options."""
    parser.add_argument("--exercise", required=True, help=f"one of: {', '.join(EXERCISES)}")
    parser.add_argument("--reps", type=int, required=True, help="number of repetitions (1-500)")
    parser.add_argument("--device", default="kinect2", help="kinect1 or kinect2 (default kinect2)")
    parser.add_argument("--view", type=int, default=0, help="camera angle from the front, degrees: 0, 30 or 60")
    parser.add_argument("--pose", help="sitting or standing (default: the exercise's natural pose)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--rate", type=float, default=30.0, help="frame rate, Hz (default 30)")
    parser.add_argument("-o", "--output", type=Path, required=True, help="measured recording: .csv or .khs")
    parser.add_argument("--truth", type=Path, help="also write the exact truth: .csv or .khs")


def _check_output(path: Path) -> None:
    if path.suffix.lower() not in (".csv", ".khs"):
        raise ValueError(f"{path}: cannot tell the output format from the extension; use .csv or .khs")


def run(args: argparse.Namespace) -> int:
    """Simulates and writes the measured (and truth) recordings; writes nothing when any argument is wrong."""
    kinect_noise.check_setting(args.device, args.view, args.pose or "standing")
    for path in (args.output, args.truth):
        if path is not None:
            _check_output(path)
    if args.truth is not None and args.truth.resolve() == args.output.resolve():
        raise ValueError(f"--truth and -o name the same file {args.output}")
    measured, truth, mask = simulate(
        args.exercise, args.reps, device=args.device, view_deg=args.view, pose=args.pose, seed=args.seed,
        rate_hz=args.rate,
    )  # fmt: skip
    formats.write(measured, args.output)
    if args.truth is not None:
        try:
            formats.write(truth, args.truth)
        except BaseException:
            with contextlib.suppress(FileNotFoundError):
                args.output.unlink()  # both files or neither
            raise
    print(
        f"{args.exercise} x{args.reps} ({measured.meta.pose}, {args.device}, {args.view} deg): {measured.n_frames} "
        f"frames, {measured.duration:.1f} s, {int(mask.sum())} outlier joint-frames -> {args.output}",
        file=sys.stderr,
    )
    return 0
