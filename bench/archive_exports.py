"""What each session's exports cost the patient's archive (backend.records.archive, format 3), per format.

    .venv/bin/python -m bench.archive_exports [--reps 10 60] [--seeds 1 2 3] [--repeats 5]

Per simulated squat set of --reps repetitions (10: about 45 s, 60: about 4.5 min) and seed: the CPU time (median of
--repeats, process time) of what the archive does for one session with a stored metrics document (decode the .khs,
read the document, build csv and fhir), and of the trc and bvh files it leaves out; sizes deflated as in the zip
(level 6), beside the .khs file's size.
"""

from __future__ import annotations

import argparse
import statistics
import time
import zlib
from collections.abc import Callable
from typing import Any

from backend.sessions.detail import analysis_document, decode_stored
from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.export.files import ExportFile, export
from kinect_agent.formats.session_file import SessionPayload
from tests.backend.khs_files import make_khs

LIMITS = {"max_frames": 10**6, "max_decoded_bytes": 1 << 30}


def _cpu(fn: Callable[[], list[ExportFile]], repeats: int) -> tuple[float, list[ExportFile]]:
    times: list[float] = []
    out: list[ExportFile] = []
    for _ in range(repeats):
        t0 = time.process_time()
        out = fn()
        times.append(time.process_time() - t0)
    return statistics.median(times), out


def _deflated(files: list[ExportFile]) -> int:
    return sum(len(zlib.compress(f.data, 6)) for f in files)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, nargs="+", default=[10, 60])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    spec = EXERCISES["squat"]
    print("reps seed frames khs_B | csv+fhir_cpu_ms deflated_B | trc+bvh_cpu_ms deflated_B")
    for reps in args.reps:
        for seed in args.seeds:
            data = make_khs("squat", reps, seed=seed)
            payload = decode_stored(data, session_id=1, **LIMITS)
            document, _ = analysis_document(payload, spec, None)
            stored = document.model_dump(mode="json") if document is not None else None

            def kept(data: bytes = data, stored: dict[str, Any] | None = stored) -> list[ExportFile]:
                p = decode_stored(data, session_id=1, **LIMITS)
                doc, _ = analysis_document(p, spec, stored)
                return [export(f, p, document=doc) for f in ("csv", "fhir")]

            def left_out(payload: SessionPayload = payload) -> list[ExportFile]:
                return [export(f, payload) for f in ("trc", "bvh")]

            cpu_kept, files = _cpu(kept, args.repeats)
            cpu_out, others = _cpu(left_out, args.repeats)
            print(f"{reps} {seed} {payload.raw.n_frames} {len(data)} | {cpu_kept * 1000:.0f} {_deflated(files)} | "
                  f"{cpu_out * 1000:.0f} {_deflated(others)}")  # fmt: skip


if __name__ == "__main__":
    main()
