"""`kinect-agent convert IN -o OUT`: any supported recording to Skeleton CSV or a session file."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from kinect_agent import formats

NAME = "convert"
HELP = "Convert a recording (format auto-detected) to Skeleton CSV (.csv) or a session file (.khs)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares the convert options."""
    known = ", ".join(sorted(formats.available()))
    parser.add_argument("input", type=Path, help="recording file (or UI-PRMD folder)")
    parser.add_argument("-o", "--output", type=Path, required=True, help="output file: .csv or .khs")
    parser.add_argument("--format", help=f"input format instead of detecting it: {known}")
    parser.add_argument("--output-format", help="output format instead of the extension: csv or session")


def run(args: argparse.Namespace) -> int:
    """Reads the input and writes the output atomically."""
    rec = formats.read(args.input, args.format)
    formats.write(rec, args.output, args.output_format)
    print(
        f"{args.input} -> {args.output}: {rec.n_frames} frames, {rec.duration:.2f} s, device {rec.meta.device}",
        file=sys.stderr,
    )
    return 0
