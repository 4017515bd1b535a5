"""`kinect-agent filter IN -o OUT.csv [--params OUT.json] [--online]`: outlier removal + four-pass kinematic UKF.

Reads any supported recording (format detected or named), writes the filtered recording as Skeleton CSV with the
input's frames and times and every joint of every frame filled (state 2 = observed, 1 = filled by the model), and
optionally the kinematic parameters as JSON with the data-quality summary under "quality" (outlier fraction per
joint, segment-length SD before and after, in mm). Both outputs are written atomically and only after filtering
succeeded, so an error leaves neither behind. The same summary, short, goes to stderr.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from kinect_agent import formats
from kinect_agent.cli import cycle_collector_paused
from kinect_agent.errors import AgentError
from kinect_agent.formats import skeleton_csv
from kinect_agent.formats._atomic import atomic_open
from kinect_agent.processing.config import SMOOTHERS, PipelineConfig
from kinect_agent.processing.pipeline import filter_recording, process

NAME = "filter"
HELP = "Remove tracking-loss outliers and smooth a recording with the four-pass kinematic UKF."
_PROGRESS_MIN_FRAMES = 1000  # show a progress bar for recordings at least this long


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares the filter options."""
    known = ", ".join(sorted(formats.available()))
    parser.add_argument("input", type=Path, help="recording file (or UI-PRMD folder)")
    parser.add_argument("-o", "--output", type=Path, required=True, help="filtered recording, Skeleton CSV (.csv)")
    parser.add_argument("--params", type=Path, help="also write the kinematic parameters as JSON here")
    parser.add_argument("--online", action="store_true", help="forward pass only, as the live feedback sees it")
    parser.add_argument("--format", help=f"input format instead of detecting it: {known}")
    parser.add_argument(
        "--smoother",
        choices=SMOOTHERS,
        help="how the last passes combine: urts = unscented RTS smoother (default, measured better), "
        "four_pass = the paper's backward pass",
    )
    parser.add_argument(
        "--no-excursions", action="store_true",
        help="do not remove sustained tracking loss (a joint that jumps away faster than a body moves, sits there "
        "and jumps back); only the temporal mixture model",
    )  # fmt: skip
    parser.add_argument("--no-progress", action="store_true", help="no progress bar (there is none unless stderr is "
                        "a terminal)")  # fmt: skip


def _progress_bar(n_frames: int, enabled: bool) -> tuple[Any, Callable[[int, int], None] | None]:
    """Returns (bar, progress callback) for a long recording when stderr is a terminal, else (None, None): a log
    file would get a line per update."""
    if not enabled or n_frames < _PROGRESS_MIN_FRAMES or not sys.stderr.isatty():
        return None, None
    from tqdm import tqdm

    bar = tqdm(total=1, unit="step", file=sys.stderr, desc="filter", leave=False)

    def progress(done: int, total: int) -> None:
        if bar.total != total:
            bar.total = total
        bar.n = done
        bar.refresh()

    return bar, progress


def run(args: argparse.Namespace) -> int:
    """Filters the input and writes the outputs atomically; returns 0."""
    with cycle_collector_paused():
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    if args.output.suffix.lower() != ".csv":
        raise AgentError(f"{args.output}: the filtered recording is written as Skeleton CSV; use a .csv name")
    if args.params is not None and args.params.resolve() in (
        args.output.resolve(),
        skeleton_csv.sidecar_path(args.output).resolve(),
    ):
        raise AgentError(f"{args.params}: --params must differ from the output file and its metadata sidecar")
    rec = formats.read(args.input, args.format)
    smoother = {"smoother": args.smoother} if args.smoother else {}
    excursions = not args.no_excursions
    config = PipelineConfig(**smoother, outlier_excursions=excursions, online_excursions=excursions)
    bar, progress = _progress_bar(rec.n_frames, not args.no_progress)
    params_text = None
    try:  # without --params, the parameters and angle SDs nobody reads are not built (the same recording)
        if args.params:
            full = process(rec, online=args.online, config=config, progress=progress)
            filtered, q = full.filtered, full.quality
            # Serialise both outputs before writing either, so a failure leaves nothing behind.
            params_text = json.dumps({**full.params.to_json(), "quality": q}, separators=(",", ":"))
        else:
            only = filter_recording(rec, online=args.online, config=config, progress=progress)
            filtered, q = only.filtered, only.quality
    finally:
        if bar is not None:
            bar.close()
    formats.write(filtered, args.output, "csv")
    if params_text is not None:
        try:
            with atomic_open(args.params, "w", encoding="utf-8") as f:
                f.write(params_text)
        except BaseException:
            args.output.unlink(missing_ok=True)
            raise
    print(
        f"{args.input} -> {args.output}: {rec.n_frames} frames, {q['n_outliers']} outliers removed, "
        f"{q['frames_without_observation']} frames without observation, {q['seconds']:.1f} s",
        file=sys.stderr,
    )
    print(quality_summary(q), file=sys.stderr)
    return 0


def _mean_mm(sd: dict[str, float | None]) -> float | None:
    values = [v for v in sd.values() if v is not None]
    return sum(values) / len(values) if values else None


def quality_summary(quality: dict[str, Any], top: int = 3) -> str:
    """Returns one line: mean segment-length SD before -> after (mm) and the joints that lost most samples."""
    before, after = _mean_mm(quality["segment_sd_before_mm"]), _mean_mm(quality["segment_sd_after_mm"])
    sd = "segment-length SD n/a" if before is None else f"segment-length SD {before:.1f} mm -> {after or 0.0:.1f} mm"
    worst = sorted(quality["outlier_fraction"].items(), key=lambda kv: -kv[1])[:top]
    worst = [f"{joint} {100 * frac:.1f} %" for joint, frac in worst if frac > 0]
    return f"quality: {sd}; outliers: {', '.join(worst) if worst else 'none'}"
