"""`kinect-agent capture`: record skeletons from a source (simulator, file replay, Kinect v2, Azure Kinect, webcam)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from kinect_agent import formats
from kinect_agent.sources import SOURCES, make_source, record

NAME = "capture"
HELP = "Record skeleton frames from a source for some seconds into a .csv or .khs file (written atomically)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares the capture options."""
    parser.add_argument("--source", required=True, choices=SOURCES, help="where frames come from")
    parser.add_argument("--file", type=Path, help="recording to replay (--source replay)")
    parser.add_argument(
        "video", nargs="?", type=Path, help="video file to analyse instead of a camera (--source webcam)"
    )
    parser.add_argument("--camera", type=int, help="camera index (--source webcam; default 0)")
    parser.add_argument("--model", choices=("lite", "full"), help="pose model (--source webcam; default lite)")
    parser.add_argument("--exercise", help="exercise to simulate (--source simulator)")
    parser.add_argument("--device", help="simulated device kinect1|kinect2, or azure_kinect|femto")
    parser.add_argument("--seed", type=int, default=0, help="simulator seed (default 0)")
    parser.add_argument("--seconds", type=float, required=True, help="how long to record, seconds")
    parser.add_argument("--fast", action="store_true", help="replay/simulate as fast as possible, not in real time")
    parser.add_argument("-o", "--output", type=Path, required=True, help="output file: .csv or .khs")


def run(args: argparse.Namespace) -> int:
    """Opens the source, records, writes the output atomically (nothing is written on failure)."""
    if not args.seconds > 0 or args.seconds != args.seconds or args.seconds == float("inf"):
        raise ValueError(f"--seconds must be a positive number, got {args.seconds}")
    if args.output.suffix.lower() not in (".csv", ".khs"):
        raise ValueError(f"{args.output}: cannot tell the output format from the extension; use .csv or .khs")
    if args.video is not None and args.source != "webcam":
        raise ValueError(f"a VIDEO file is only for --source webcam, not {args.source}")
    source = make_source(
        args.source, file=args.video if args.source == "webcam" else args.file, exercise=args.exercise,
        realtime=not args.fast, seed=args.seed, device=args.device, camera=args.camera, model=args.model,
    )  # fmt: skip
    rec = record(source, args.seconds)
    formats.write(rec, args.output)
    print(f"{args.source} -> {args.output}: {rec.n_frames} frames, {rec.duration:.2f} s", file=sys.stderr)
    return 0
