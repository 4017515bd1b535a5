"""Cost of the therapist's session page data (GET /api/v1/sessions/{id}/detail) for a 10-minute session.

The session file is bench/ingest.py's (simulated Kinect 2 squats, filtered by the agent's pipeline, cached in the
temp folder). Times backend.sessions.detail.detail_body without the database (decode, analysis, outlier model,
curves: what a job-queue worker does once, backend.sessions.prepared), then what a request does with the stored
JSON document (parse it, add the row's fields, validate as SessionDetailOut), and prints the JSON body's size,
plain and gzipped.

    python bench/session_detail.py [--minutes 10]
"""

from __future__ import annotations

import argparse
import datetime as dt
import gzip
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:  # `python bench/session_detail.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT_DIR))

from backend.sessions import detail, prepared  # noqa: E402
from backend.sessions.metrics import json_ready  # noqa: E402
from backend.sessions.models import ExerciseSession  # noqa: E402
from backend.sessions.schemas import SessionDetailOut  # noqa: E402
from bench.ingest import session_file  # noqa: E402
from kinect_agent.analysis.exercise import EXERCISES  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    """Runs the benchmark and prints its numbers; returns 0."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0, help="session length (default 10)")
    args = parser.parse_args(argv)
    data = session_file(args.minutes, Path(tempfile.gettempdir()))
    session = ExerciseSession(id=1, patient_id=1, started_at=dt.datetime(2026, 11, 20, tzinfo=dt.UTC),
                              status="processed", processing_version="bench", processing_params={})  # fmt: skip
    limits = {"max_frames": 10**6, "max_decoded_bytes": 2**30}
    payload = detail.decode_stored(data, session_id=1, **limits)
    spec = EXERCISES["squat"]
    started = time.perf_counter()
    report, _ = detail.analysis_document(payload, spec, None)
    stored = report.model_dump(mode="json") if report is not None else None
    analysis_s = time.perf_counter() - started
    started = time.perf_counter()
    body = detail.detail_body(session, "squat", stored, data, **limits)
    build_s = time.perf_counter() - started
    text = SessionDetailOut(**json_ready(body)).model_dump_json()
    row = (session, "squat", None, None, None, stored)
    reads = []
    for _ in range(7):
        started = time.perf_counter()
        SessionDetailOut.model_validate(prepared.with_row(json.loads(text), row))
        reads.append(time.perf_counter() - started)
    points = sum(len(c["t_s"]) for c in body["curves"])
    print(f"session: {args.minutes:g} min, {payload.raw.n_frames} frames, file {len(data)} bytes")
    print(f"analysis document (done once at upload): {analysis_s:.2f} s")
    print(
        f"detail body, built by the worker: {build_s:.2f} s; "
        f"read stored (median of 7): {statistics.median(reads):.3f} s"
    )
    print(f"JSON body: {len(text)} bytes, gzipped {len(gzip.compress(text.encode()))} bytes")
    columns = len(body["quality"]["outlier_strip"]["t_s"])
    print(f"curves: {len(body['curves'])} with {points} points; outlier strip: {columns} columns")
    json.dump({"build_s": build_s, "read_s": statistics.median(reads), "json_bytes": len(text)}, sys.stdout)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
