"""The server's part of a camera set's frame -> count: the time from a batch of landmarks sent to its answer (the
live count), sent as the camera page sends them, against the real app (uvicorn, the demo clinic, SQLite or
PostgreSQL).

A fresh server is started for each run, as after an install or a restart, with nothing set in its environment
beyond the database: the live filter's compiled code is whatever the server readies itself. The demo's camera
patient starts a squat set, and frames of synthetic squats (tests/backend/camera/landmarks.py) come at --fps in real
time; every 0.1 s (the page's batching) the frames that came are sent as one batch, and, as the page does, the
next batch waits for the answer in flight. --wait: seconds between the server answering /healthz and the set's
start (a patient needs some seconds to log in and place themself; 0 is the worst case). Printed per run: the
first batch's round trip (what start-up costs reach), then p50/p95/max of all batches.

    .venv/bin/python bench/camera_batches.py [--runs 3] [--seconds 12] [--fps 15] [--wait 5] [--db URL]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import httpx  # noqa: E402

from backend.camera.limits import CONSENT_VERSION  # noqa: E402
from backend.demo import CAMERA_PATIENT, DEMO_PASSWORD  # noqa: E402
from bench.camera_page import prepare  # noqa: E402
from bench.dashboard_load import percentile, start_server, stop_server  # noqa: E402
from tests.backend.camera.landmarks import IMAGE_SIZE, squats  # noqa: E402

FLUSH_S = 0.1  # the page's batching interval (frontend/static/camera_page.js FLUSH_MS)


def one_set(base: str, seconds: float, fps: float) -> list[float]:
    """Runs one set of `seconds`; returns each batch's round trip (s), in order."""
    frames = squats(int(seconds / 2.5) + 1, fps=fps)
    with httpx.Client(base_url=base, timeout=300) as c:
        me = c.post("/api/v1/auth/login", json={"email": CAMERA_PATIENT[0], "password": DEMO_PASSWORD}).json()
        c.headers["X-CSRF-Token"] = me["csrf_token"]
        plans = c.get(f"/api/v1/patients/{me['user']['id']}/plans").json()["items"]
        item = next(i["id"] for p in plans for i in p["items"] if i["exercise_slug"] == "squat")
        c.post("/api/v1/camera/consent", json={"consent_version": CONSENT_VERSION}).raise_for_status()
        r = c.post("/api/v1/camera/sets", json={"plan_item_id": item, "model": "pose_landmarker_lite"})
        r.raise_for_status()
        set_id, t0 = r.json()["set_id"], time.monotonic()
        trips: list[float] = []
        k = 0
        while time.monotonic() - t0 < seconds and k < len(frames):
            now = time.monotonic() - t0
            n = min(int(now * fps), len(frames)) - k  # the frames the camera gave since the last batch
            if n > 0:
                batch = [f | {"t": round((k + i + 1) / fps, 3)} for i, f in enumerate(frames[k : k + n])]
                sent = time.perf_counter()
                body = {"seq": len(trips), "version": 1, "image_size": IMAGE_SIZE, "frames": batch, "fps": fps}
                r = c.post(f"/api/v1/camera/sets/{set_id}/batches", json=body)
                trips.append(time.perf_counter() - sent)
                r.raise_for_status()
                k += n
            time.sleep(max(0.0, FLUSH_S - (time.monotonic() - t0 - now)))
        c.post(f"/api/v1/camera/sets/{set_id}/end", json={"last_seq": len(trips) - 1, "reason": "stop"})
    return trips


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=12.0)
    parser.add_argument("--fps", type=float, default=15.0)
    parser.add_argument("--wait", type=float, default=5.0)
    parser.add_argument("--port", type=int, default=8103)
    parser.add_argument("--db", default=None, help="database URL (default: SQLite in a temporary folder)")
    args = parser.parse_args(argv)
    firsts, p50s, p95s, everything = [], [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        db_url = args.db or f"sqlite:///{tmp}/bench.db"
        prepare(db_url)
        for run in range(args.runs):
            server = start_server(db_url, args.port, 1)
            try:
                time.sleep(args.wait)
                trips = [s * 1000 for s in one_set(f"http://127.0.0.1:{args.port}", args.seconds, args.fps)]
            finally:
                stop_server(server)
            rest = trips[1:] or trips
            firsts.append(trips[0])
            p50s.append(percentile(rest, 50))
            p95s.append(percentile(rest, 95))
            everything += trips
            print(f"run {run + 1}: {len(trips)} batches, first {trips[0]:.0f} ms, then p50 {p50s[-1]:.0f} ms, "
                  f"p95 {p95s[-1]:.0f} ms, max {max(rest):.0f} ms; load {os.getloadavg()[0]:.1f}",
                  flush=True)  # fmt: skip
    med = statistics.median
    print(f"\nmedian of {args.runs} runs: first batch {med(firsts):.0f} ms, p50 {med(p50s):.0f} ms, "
          f"p95 {med(p95s):.0f} ms; all batches p95 {percentile(everything, 95):.0f} ms "
          f"({len(everything)} batches)")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
