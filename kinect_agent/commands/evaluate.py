"""`kinect-agent evaluate --kinect FILE --mocap FILE [--view DEG] [--pose sitting|standing] --out DIR`: the paper's
accuracy study (Wang et al., section 3.1) for your own Kinect against simultaneous motion capture."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    from kinect_agent.evaluation.pairs import PairSpec

T = TypeVar("T")


NAME = "evaluate"
HELP = ("Measure a Kinect against simultaneous motion capture: time alignment, registration, the paper's tables "
        "and figures (report.md, CSV, PNG, summary.json).")  # fmt: skip


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares the evaluate options."""
    parser.add_argument("--kinect", type=Path, action="append", default=[], help="Kinect recording (repeatable)")
    parser.add_argument("--mocap", type=Path, action="append", default=[],
                        help="mocap recording of the same trial, in --kinect order (repeatable)")  # fmt: skip
    parser.add_argument("--pairs", type=Path, action="append", default=[],
                        help="folder of pairs: X-Kinect-* with X-Vicon-*, .../Kinect/... with .../Vicon/..., or "
                             "NAME_kinect.* with NAME_mocap.* (repeatable)")  # fmt: skip
    parser.add_argument(
        "--view",
        type=float,
        action="append",
        default=[],
        help="view angle from the frontal direction, degrees (one for all pairs, or one per pair)",
    )
    parser.add_argument(
        "--pose",
        choices=("sitting", "standing"),
        action="append",
        default=[],
        help="pose of the exercises (one for all pairs, or one per pair; default standing)",
    )
    parser.add_argument("--out", type=Path, required=True, help="folder for report.md, the CSV tables, the figures")
    parser.add_argument("--kinect-format", help="Kinect file format (default: detected)")
    parser.add_argument("--mocap-format", help="mocap file format (default: detected)")
    parser.add_argument(
        "--no-registration",
        action="store_true",
        help="the mocap is already in the Kinect camera frame (calibrated): align in time only",
    )
    parser.add_argument("--max-lag", type=float, default=2.0, help="largest time offset searched, s (default 2)")
    parser.add_argument("--no-figures", action="store_true", help="skip the PNG figures (no matplotlib needed)")


def _per_pair(values: list[T], n: int, default: T, what: str) -> list[T]:
    if not values:
        return [default] * n
    if len(values) == 1:
        return values * n
    if len(values) != n:
        raise ValueError(f"give one {what} for all pairs or one per pair ({n}); got {len(values)}")
    return values


def specs(args: argparse.Namespace) -> list[PairSpec]:
    """Returns the PairSpecs the arguments name."""
    from kinect_agent.evaluation.pairs import PairSpec, find_pairs

    if len(args.kinect) != len(args.mocap):
        raise ValueError(f"--kinect and --mocap must come in pairs; got {len(args.kinect)} and {len(args.mocap)}")
    files = list(zip(args.kinect, args.mocap, strict=True))
    for folder in args.pairs:
        found = find_pairs(folder)
        if not found:
            raise ValueError(f"{folder}: no Kinect/mocap pairs found (see --help for the naming rules)")
        files += found
    if not files:
        raise ValueError("nothing to evaluate: give --kinect FILE --mocap FILE or --pairs DIR")
    views = _per_pair(args.view, len(files), 0.0, "--view")
    poses = _per_pair(args.pose, len(files), "standing", "--pose")
    return [PairSpec(k, m, float(v), p, args.kinect_format, args.mocap_format)
            for (k, m), v, p in zip(files, views, poses, strict=True)]  # fmt: skip


def run(args: argparse.Namespace) -> int:
    """Evaluates the pairs, writes the report and prints where it went; 1 when every pair was refused."""
    from kinect_agent.evaluation.report import NothingAligned, evaluate

    try:
        pairs = specs(args)
    except FileNotFoundError as exc:
        raise ValueError(str(exc)) from None
    try:
        outcome = evaluate(pairs, args.out, rigid=not args.no_registration, max_lag_s=args.max_lag,
                           draw=not args.no_figures)  # fmt: skip
    except NothingAligned as exc:
        print(f"kinect-agent evaluate: {exc}", file=sys.stderr)
        return 1
    for r in outcome.refused:
        print(f"kinect-agent evaluate: {r}", file=sys.stderr)
    report = args.out / "report.md"
    print(f"{len(outcome.errors)} pair(s) evaluated, {len(outcome.refused)} refused; report in {report}",
          file=sys.stderr)  # fmt: skip
    return 0
