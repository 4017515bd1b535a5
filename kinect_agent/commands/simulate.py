"""`kinect-agent simulate`: a simulated exercise session, as the Kinect would measure it, plus the exact truth.

The motion comes from the kinematic model (--exercise, --reps) or from any recording (--from FILE, e.g. optical
mocap of ../shared/data), which then is the truth the simulated Kinect measures.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path

import numpy as np

from kinect_agent import formats
from kinect_agent.recording import Recording
from kinect_agent.sources import kinect_noise
from kinect_agent.sources.mocap_truth import truth_from_recording
from kinect_agent.sources.simulator import EXERCISES, simulate

NAME = "simulate"
HELP = "Simulate an exercise session measured by a Kinect (errors calibrated on Wang et al.'s tables)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares the simulate options."""
    parser.add_argument("--exercise", help=f"one of: {', '.join(EXERCISES)}")
    parser.add_argument("--reps", type=int, help="number of repetitions (1-500)")
    parser.add_argument(
        "--from", dest="source", type=Path, metavar="FILE",
        help="take the motion from this recording (any supported format) instead of --exercise/--reps",
    )  # fmt: skip
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


def _measure(args: argparse.Namespace) -> tuple[Recording, Recording, np.ndarray]:
    """Returns (measured, truth, outlier mask (T, J) bool) for the motion the arguments name."""
    if args.source is None:
        if args.exercise is None or args.reps is None:
            raise ValueError("give --exercise and --reps, or --from FILE")
        return simulate(
            args.exercise, args.reps, device=args.device, view_deg=args.view, pose=args.pose, seed=args.seed,
            rate_hz=args.rate,
        )  # fmt: skip
    if args.exercise is not None or args.reps is not None:
        raise ValueError("--from FILE takes the motion from the file; leave out --exercise and --reps")
    truth = truth_from_recording(formats.read(args.source), view_deg=args.view, rate_hz=args.rate)
    pose = args.pose or "standing"
    rng = np.random.default_rng(args.seed)
    measured, mask = kinect_noise.add_kinect_noise(truth, device=args.device, view_deg=args.view, pose=pose, rng=rng)
    measured.meta.pose = truth.meta.pose = pose
    return measured, truth, mask


def run(args: argparse.Namespace) -> int:
    """Simulates and writes the measured (and truth) recordings; writes nothing when any argument is wrong."""
    kinect_noise.check_setting(args.device, args.view, args.pose or "standing")
    for path in (args.output, args.truth):
        if path is not None:
            _check_output(path)
    if args.truth is not None and args.truth.resolve() == args.output.resolve():
        raise ValueError(f"--truth and -o name the same file {args.output}")
    measured, truth, mask = _measure(args)
    formats.write(measured, args.output)
    if args.truth is not None:
        try:
            formats.write(truth, args.truth)
        except BaseException:
            with contextlib.suppress(FileNotFoundError):
                args.output.unlink()  # both files or neither
            raise
    what = args.source.name if args.source is not None else f"{args.exercise} x{args.reps}"
    print(
        f"{what} ({measured.meta.pose}, {args.device}, {args.view} deg): {measured.n_frames} "
        f"frames, {measured.duration:.1f} s, {int(mask.sum())} outlier joint-frames -> {args.output}",
        file=sys.stderr,
    )
    return 0
