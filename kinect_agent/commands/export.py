"""`kinect-agent export SESSION.khs --format csv|trc|bvh|fhir [--out PATH] [--metrics DOC.json]`.

csv, trc and bvh need only the session file; the metrics and repetition tables of csv, and fhir, need the
session's analysis document (`coach-server analyze SESSION.khs --exercise SLUG --json`, or the "metrics" of
GET /api/v1/sessions/{id}). The output is written atomically: on any error nothing is left behind.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from pydantic import ValidationError

from kinect_agent.analysis.document import AnalysisReport, UnreadableDocument, read_report
from kinect_agent.errors import AgentError
from kinect_agent.export import fhir
from kinect_agent.export.files import FORMATS, export
from kinect_agent.formats._atomic import atomic_open
from kinect_agent.formats.session_file import read_payload

NAME = "export"
HELP = "Export a session file for other software: csv (zip of tables), trc (OpenSim), bvh, fhir (R4 Bundle)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares the export options."""
    parser.add_argument("session", type=Path, help="session file (.khs)")
    parser.add_argument("--format", required=True, choices=FORMATS, help="output format")
    parser.add_argument("--out", type=Path, help="output file (default: beside the session, named by the format)")
    parser.add_argument(
        "--metrics", type=Path, metavar="DOC.json",
        help="the session's analysis document (coach-server analyze --json): metrics.csv, repetitions.csv, fhir",
    )  # fmt: skip


def _document(path: Path | None) -> AnalysisReport | None:
    if path is None:
        return None
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise AgentError(f"{path}: cannot read the metrics document: {exc.strerror}") from None
    except (UnicodeDecodeError, ValueError) as exc:
        raise AgentError(f"{path}: the metrics document is not JSON: {exc}") from None
    except RecursionError:
        raise AgentError(f"{path}: the metrics document is nested too deeply to be an analysis document") from None
    doc = doc.get("metrics", doc) if isinstance(doc, dict) and "metrics" in doc else doc
    if not isinstance(doc, dict) or "repetitions" not in doc:
        raise AgentError(f"{path}: not an analysis document (expected an object with 'repetitions')")
    try:
        return read_report(doc)
    except (ValidationError, UnreadableDocument) as exc:
        raise AgentError(f"{path}: not an analysis document: {_first_error(exc)}") from None


def _first_error(exc: ValidationError | UnreadableDocument) -> str:
    """Returns the first problem of a document that does not validate, in one line."""
    if isinstance(exc, UnreadableDocument):
        return str(exc)
    first = exc.errors()[0]
    return f"{'.'.join(str(p) for p in first['loc'])}: {first['msg']}"


def run(args: argparse.Namespace) -> int:
    """Reads the session (and the document), exports it, writes the output atomically."""
    if not args.session.is_file():
        raise AgentError(f"{args.session}: no such session file")
    payload = read_payload(args.session)
    document = _document(args.metrics)
    context = None
    if payload.recorded_by is not None:
        context = fhir.SessionContext(
            session_id=payload.session_id,
            start=payload.created_at,
            patient_id=payload.recorded_by["patient_id"],
            device_id=payload.recorded_by["device_id"],
        )
    result = export(args.format, payload, document=document, context=context, stem=args.session.stem)
    out = args.out or args.session.with_name(result.file_name)
    with atomic_open(out, "wb") as f:
        f.write(result.data)
    print(f"{args.session} -> {out}: {args.format}, {len(result.data)} bytes", file=sys.stderr)
    return 0
