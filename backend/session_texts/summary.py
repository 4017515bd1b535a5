"""`coach-server analyze FILE --exercise NAME [--json]`: the analysis document of one recording file
(kinect_agent.analysis.report.analyze_file) as a summary in English, or as JSON with its reasons written.
"""

from __future__ import annotations

import argparse
import json
import sys

from backend.i18n import ENGLISH
from backend.session_texts import reasons
from kinect_agent.analysis.document import AnalysisReport
from kinect_agent.analysis.errors import AnalysisError
from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.analysis.reasons import Reason
from kinect_agent.analysis.report import analyze_file


def _balance_line(doc: AnalysisReport) -> str:
    """Returns the balance in one line: sway velocity with its 95 % interval, or why it was not measured."""
    b = doc.balance
    if b is None:
        missing = "" if doc.balance_missing is None else reasons.written(doc.balance_missing, ENGLISH)
        return f"balance: not measured: {missing}"
    interval = "" if b.sway_velocity_95 is None else (
        f" (95 % {100 * b.sway_velocity_95[0]:.2f}-{100 * b.sway_velocity_95[1]:.2f})"
    )  # fmt: skip
    return f"balance: sway {100 * b.sway_velocity_m_s:.2f} cm/s{interval} over {b.standing_s:.1f} s standing"


def _summary(doc: AnalysisReport) -> str:
    q = doc.quality
    lines = [
        f"{doc.exercise}: {doc.repetitions} repetitions in {doc.duration_s:.1f} s "
        f"({doc.n_frames} frames at {doc.rate_hz:.1f} Hz)",
        f"defining angle {doc.defining_angle}, median amplitude {_degrees(doc.rom_deg, doc.rom_deg_withheld)}",
        f"quality: {'ok' if q.ok else 'NOT ok'} (tracked {q.tracked_fraction:.0%}, "
        f"outliers {q.outlier_fraction:.1%}){''.join('; ' + reasons.written(r, ENGLISH) for r in q.reasons)}",
        _balance_line(doc),
    ]
    lines += [
        f"  #{r.index + 1}: {r.start_s:.2f}-{r.end_s:.2f} s, "
        + (f"amplitude {r.amplitude_deg} deg, peak {r.peak_deg} deg" if r.withheld is None
           else f"amplitude and peak withheld: {reasons.written(r.withheld, ENGLISH)}")
        + f", {r.side}"
        for r in doc.repetition_list
    ]  # fmt: skip
    return "\n".join(lines)


def _degrees(value: float | None, withheld: Reason | None) -> str:
    """Returns "12.5 deg", or why a number is withheld ("withheld: ..."), or "None"."""
    if withheld is not None:
        return f"withheld: {reasons.written(withheld, ENGLISH)}"
    return f"{value} deg" if value is not None else "None"


def build_parser() -> argparse.ArgumentParser:
    """Returns the parser of `coach-server analyze`."""
    parser = argparse.ArgumentParser(prog="coach-server analyze", description="Analyse one recording file.")
    add_arguments(parser)
    return parser


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares FILE, --exercise and --json on parser."""
    parser.add_argument("file", help="a recording in any format the agent reads (.khs, .csv, UI-PRMD, ...)")
    parser.add_argument("--exercise", required=True, help=f"exercise slug ({', '.join(sorted(EXERCISES))})")
    parser.add_argument("--json", action="store_true", help="print the full JSON document instead of a summary")


def main(argv: list[str] | None = None) -> int:
    """Runs `coach-server analyze`; prints the report; returns 0, or 2 after a one-line error on stderr."""
    try:
        args = build_parser().parse_args(sys.argv[1:] if argv is None else list(argv))
    except SystemExit as exc:  # --help (0) or a usage error (2, already printed by argparse)
        return int(exc.code or 0)
    return run(args)


def run(args: argparse.Namespace) -> int:
    """Analyses args.file as args.exercise; prints the report; returns 0, or 2 after a one-line error."""
    try:
        doc = analyze_file(args.file, args.exercise)
    except AnalysisError as exc:
        print(f"coach-server analyze: error: {exc}", file=sys.stderr)
        return 2
    document = reasons.with_texts(doc, ENGLISH).model_dump(mode="json") | {"source": str(args.file)}
    print(json.dumps(document, indent=2, allow_nan=False) if args.json else _summary(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
