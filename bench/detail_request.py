"""Time of GET /sessions/{id}/detail for a session like the demo's, through the real server (prints numbers).

    .venv/bin/python bench/detail_request.py [--runs 7] [--json OUT]

Setup (not measured): the demo clinic (`coach-server migrate`, `seed-demo`) in a SQLite file in a temp folder, the
real server (uvicorn, one process, with the embedded worker: COACH_EMBEDDED_WORKER=true, as the demo runs it), a
device paired with the demo patient Maria uploading sessions as the demo's agents do (the simulator's set of
6–10 repetitions, filtered by the agent's pipeline: kinect_agent.capture.make_payload). Per session: the time from
the upload's answer until /detail first answers 200 (when a worker prepares it: asked every 0.1 s), then `--runs`
further requests, as her therapist; the median of those per session, and over the sessions.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import httpx

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:
    sys.path.insert(0, str(ROOT_DIR))

from bench.crowd import demo_clinic  # noqa: E402
from bench.dashboard_load import free_port, start_server, stop_server  # noqa: E402
from bench.worst_file import ADMIN, PATIENT, THERAPIST, _client, _device_token  # noqa: E402
from kinect_agent.capture import make_payload  # noqa: E402
from kinect_agent.formats import session_file as sf  # noqa: E402
from kinect_agent.sources.simulator import simulate  # noqa: E402

DEMO_SETS = (("squat", 8, 3), ("squat", 6, 4), ("squat", 10, 5))  # (exercise, repetitions, seed): Maria's plan


def demo_file(exercise: str, reps: int, seed: int) -> bytes:
    """Returns the .khs bytes a demo agent uploads for one set (simulated, filtered by the agent's pipeline)."""
    measured, _, _ = simulate(exercise, reps, seed=seed)
    return sf.encode(make_payload(measured, created_at="2026-11-27T05:00:00Z"))


def run(url: str, files: list[bytes], runs: int) -> list[dict[str, float]]:
    """Starts the server on url, uploads each file and times its /detail; returns one row per session."""
    port = free_port()
    base = f"http://127.0.0.1:{port}"
    server = start_server(url, port, workers=1)
    rows = []
    try:
        admin, therapist, patient = _client(base, ADMIN), _client(base, THERAPIST), _client(base, PATIENT)
        pid = patient.get("/api/v1/users/me").json()["id"]
        device = {"Authorization": f"Bearer {_device_token(base, admin, pid)}",
                  "Content-Type": "application/octet-stream"}  # fmt: skip
        for data in files:
            r = httpx.post(f"{base}/api/v1/sessions", params={"exercise": "squat"}, content=data, headers=device,
                           timeout=600)  # fmt: skip
            r.raise_for_status()
            sid = r.json()["id"]
            started, asked = time.perf_counter(), 0
            while True:
                asked += 1
                first = therapist.get(f"/api/v1/sessions/{sid}/detail")
                if first.status_code != 202:
                    break
                time.sleep(0.1)
            ready_s = time.perf_counter() - started
            if first.status_code != 200:
                raise SystemExit(f"/detail answered {first.status_code}: {first.text[:300]}")
            times = []
            for _ in range(runs):
                t0 = time.perf_counter()
                therapist.get(f"/api/v1/sessions/{sid}/detail").raise_for_status()
                times.append(time.perf_counter() - t0)
            row: dict[str, float] = {
                "session": sid, "frames": first.json()["n_frames"], "first_200_s": round(ready_s, 3), "asked": asked,
                "median_s": round(statistics.median(times), 4), "min_s": round(min(times), 4),
                "max_s": round(max(times), 4),
            }  # fmt: skip
            print(row, flush=True)
            rows.append(row)
    finally:
        stop_server(server)
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7, help="requests per session after the first 200 (default 7)")
    parser.add_argument("--json", type=Path, help="also write the numbers to this JSON file")
    args = parser.parse_args()
    files = [demo_file(*s) for s in DEMO_SETS]
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["COACH_EMBEDDED_WORKER"] = "true"
        os.environ["COACH_STORAGE_DIR"] = str(Path(tmp) / "objects")
        rows = run(demo_clinic(None, Path(tmp)), files, args.runs)
    medians = [r["median_s"] for r in rows]
    firsts = [r["first_200_s"] for r in rows]
    print(f"GET /detail, {len(rows)} demo sessions x {args.runs} requests: median {statistics.median(medians):.4f} s "
          f"(per session {medians}); upload answered -> first 200: median {statistics.median(firsts):.2f} s "
          f"(per session {firsts})")  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
