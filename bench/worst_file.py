"""The worst session file the server accepts, read through every endpoint of the real server (prints numbers).

    .venv/bin/python bench/worst_file.py [--db sqlite] [--db URL] [--only NAME ...] [--json OUT] [--cache FILE]
                                         [--at-export-limit] [--repeat N]

The file: the most frames (COACH_SESSION_MAX_FRAMES, 216 000) over the longest duration (COACH_SESSION_MAX_DURATION_S,
2 h), i.e. 30 Hz, the rate at which the server analyses every frame (it thins above 40 Hz, work_budget); a squat
set tiled over two hours, raw positions with 2 cm noise and 3 % of frames carrying outliers (a joint thrown up to
1 m), the noise-free recording as the filtered one. It is within the upload (32 MiB) and decoded-size limits.
--at-export-limit: the same kind of file with COACH_EXPORT_DIRECT_MAX_FRAMES frames over COACH_EXPORT_DIRECT_MAX_S,
the longest whose downloads are built in the request (held to work_budget.EXPORT_IN_REQUEST, not per 10 minutes).

Setup (not measured): the demo clinic (`coach-server migrate`, `seed-demo`) in a SQLite file in a temp folder, or in
the PostgreSQL database of --db (dropped and recreated; its name must contain "bench"); the real server (uvicorn,
one process, bench.dashboard_load.start_server) and two `coach-server worker`s: one for the exports (`--kinds
export`), one for the other jobs (the session page's detail, queued by the upload, and the replays; with --only
and neither named, none). A device is paired with the demo patient Maria, uploads the file; the worker's build of
the detail is measured until /detail answers 200; each export is asked for until it is not 202 (its worker's
build) and then read (`--repeat` times, median), or read in the request for a short recording; then each other
endpoint is requested once, as Maria, or as her therapist where only staff may ask, then the replay builds (one
skeleton, both) and their reads. For each request the CPU time of the process that does the work (the server;
the worker for a build, from the upload's answer or the first ask until the answer is ready) is read from
/proc/<pid>/stat, and its peak resident memory above the request's start from /proc/<pid>/status (VmHWM, reset
through /proc/<pid>/clear_refs before each request). Budgets (backend.session_texts.work_budget, docs/deployment.md):
upload, replay and export builds their own, every other read of the session the session page's ("detail"), per
started 10 minutes of recording. Exit status 1 when a request fails (4xx, 5xx) or exceeds its budget.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import uuid
from collections.abc import Callable
from dataclasses import asdict, dataclass
from functools import partial
from pathlib import Path

import httpx
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from backend.config import Settings  # noqa: E402
from backend.demo import DEMO_PASSWORD  # noqa: E402
from backend.jobs.worker import KINDS  # noqa: E402
from backend.session_texts import work_budget  # noqa: E402
from backend.sessions import prepared_export  # noqa: E402
from bench.crowd import demo_clinic  # noqa: E402
from bench.dashboard_load import ROOT, free_port, start_server, stop_server  # noqa: E402
from kinect_agent.formats import session_file as sf  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402
from kinect_agent.sources.simulator import simulate  # noqa: E402

ADMIN, THERAPIST, PATIENT = "admin@demo.clinic", "therapist@demo.clinic", "maria@demo.clinic"  # Maria's therapist
NOISE_M = 0.02  # SD of the raw positions' noise, m
OUTLIER_SHARE = 0.03  # frames with one joint thrown away
OUTLIER_M = 1.0  # the largest throw, m
TICK_S = 1 / os.sysconf("SC_CLK_TCK")
PAGE = os.sysconf("SC_PAGE_SIZE")


# ------------------------------------------------------------------------------------------------ the file


def _tiled(rec: Recording, n: int, period_s: float) -> Recording:
    """Returns rec's frames repeated to n frames, period_s apart."""
    reps = -(-n // rec.n_frames)
    return rec.replace(t=np.arange(n) * period_s, positions=np.tile(rec.positions, (reps, 1, 1))[:n],
                       state=np.tile(rec.state, (reps, 1))[:n])  # fmt: skip


def worst_file(n_frames: int, duration_s: float, seed: int = 27) -> bytes:
    """Returns the .khs bytes of n_frames frames evenly over duration_s: noisy raw with outliers, clean filtered."""
    measured, truth, _ = simulate("squat", 10, seed=seed)
    period = duration_s / n_frames
    clean = _tiled(truth, n_frames, period)
    rng = np.random.default_rng(seed)
    positions = clean.positions + rng.normal(0.0, NOISE_M, clean.positions.shape)  # (T, J, 3) m
    hit = np.flatnonzero(rng.random(n_frames) < OUTLIER_SHARE)
    joints = rng.integers(0, positions.shape[1], len(hit))
    positions[hit, joints] += rng.uniform(-OUTLIER_M, OUTLIER_M, (len(hit), 3))
    raw = _tiled(measured, n_frames, period).replace(positions=positions)
    payload = sf.SessionPayload(session_id=str(uuid.uuid4()), raw=raw, filtered=clean, params={},
                                created_at="2026-11-27T05:00:00Z")  # fmt: skip
    return sf.encode(payload)


# ------------------------------------------------------------------------------------------------ measuring


class ProcessMeter:
    """CPU seconds and peak resident bytes of another process (same user) over a stretch of time."""

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self.cpu0 = 0.0
        self.rss0 = 0

    def cpu_s(self) -> float:
        """Returns the process's user + system CPU time so far, s (all its threads)."""
        with open(f"/proc/{self.pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) * TICK_S

    def _status(self, key: str) -> int:
        with open(f"/proc/{self.pid}/status") as f:
            for line in f:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) * 1024
        raise RuntimeError(f"/proc/{self.pid}/status has no {key}")

    def start(self) -> None:
        """Resets the process's peak RSS (clear_refs 5) and notes its CPU time and RSS now."""
        with open(f"/proc/{self.pid}/clear_refs", "w") as f:
            f.write("5")
        self.cpu0, self.rss0 = self.cpu_s(), self._status("VmRSS")

    def stop(self) -> tuple[float, int]:
        """Returns (CPU seconds, peak bytes above the start's RSS) since start()."""
        return self.cpu_s() - self.cpu0, max(0, self._status("VmHWM") - self.rss0)


@dataclass
class Measured:
    """One request: what was asked, its answer, its cost and budget."""

    endpoint: str
    status: int
    answer_mib: float
    wall_s: float
    cpu_s: float
    peak_mib: float
    budget_cpu_s: float
    budget_mib: float

    @property
    def failures(self) -> list[str]:
        out = [f"{self.endpoint} answered {self.status}"] if self.status >= 400 else []
        if self.cpu_s > self.budget_cpu_s:
            out.append(f"{self.endpoint} {self.cpu_s:.1f} s CPU > {self.budget_cpu_s:g} s")
        if self.peak_mib > self.budget_mib:
            out.append(f"{self.endpoint} {self.peak_mib:.0f} MiB > {self.budget_mib:.0f} MiB")
        return out


def measure(
    endpoint: str, meter: ProcessMeter, budget: tuple[float, int], send: Callable[[], httpx.Response]
) -> tuple[Measured, httpx.Response]:
    """Returns (Measured, response) of one request whose work runs in meter's process."""
    t0 = time.perf_counter()
    meter.start()
    response = send()
    cpu, peak = meter.stop()
    wall = time.perf_counter() - t0
    row = Measured(endpoint, response.status_code, round(len(response.content) / 2**20, 2), round(wall, 2),
                   round(cpu, 2), round(peak / 2**20, 1), budget[0], budget[1] / 2**20)  # fmt: skip
    return row, response


# ------------------------------------------------------------------------------------------------ the run


def _client(base: str, email: str) -> httpx.Client:
    client = httpx.Client(base_url=base, timeout=1800)
    client.post("/api/v1/auth/login", json={"email": email, "password": DEMO_PASSWORD}).raise_for_status()
    client.headers["X-CSRF-Token"] = client.get("/api/v1/auth/csrf").json()["csrf_token"]
    return client


def _device_token(base: str, admin: httpx.Client, patient_id: int) -> str:
    code = admin.post(f"/api/v1/patients/{patient_id}/pairing-codes").json()["code"]
    r = httpx.post(f"{base}/api/v1/devices/pair", json={"code": code, "name": "worst file"}, timeout=60)
    r.raise_for_status()
    return r.json()["token"]


def _replay_built(patient: httpx.Client, sid: int, layer: str = "") -> httpx.Response:
    """Queues the replay build (of one skeleton alone: layer) and waits until the worker has built it (or failed);
    returns the last state."""
    query = f"?layer={layer}" if layer else ""
    while True:
        r = patient.get(f"/api/v1/sessions/{sid}/replay/state{query}")
        if r.status_code != 200 or r.json()["state"] != "preparing":
            return r
        time.sleep(0.5)


def _detail_built(client: httpx.Client, sid: int) -> httpx.Response:
    """Waits until /detail answers something else than 202 (its build queued by the upload); returns that answer."""
    while True:
        r = client.get(f"/api/v1/sessions/{sid}/detail")
        if r.status_code != 202:
            return r
        time.sleep(0.5)


def run(url: str, data: bytes, duration_s: float, n_frames: int, only: list[str], repeat: int = 1) -> list[Measured]:
    """Starts server and workers on the database url, uploads data, reads it through every endpoint (those whose
    name contains one of `only`, when given; the export reads `repeat` times, median); returns rows."""
    settings = Settings()
    port = free_port()
    base = f"http://127.0.0.1:{port}"
    server = start_server(url, port, workers=1)
    env = {**os.environ, "COACH_DATABASE_URL": url, "COACH_ENVIRONMENT": "local"}
    coach = str(Path(sys.executable).parent / "coach-server")
    # one worker for the exports, one for everything else: each build is measured on the process that does it
    others = [k for k in KINDS if k != "export"]
    builds = not only or any(w in o for o in only for w in ("detail", "replay"))  # else only the exports' worker
    worker = subprocess.Popen([coach, "worker", "--kinds", *(others if builds else ["camera_end"])], env=env, cwd=ROOT,
                              stderr=subprocess.DEVNULL)  # fmt: skip
    exporter = subprocess.Popen([coach, "worker", "--kinds", "export"], env=env, cwd=ROOT, stderr=subprocess.DEVNULL)
    rows: list[Measured] = []
    try:
        admin, therapist, patient = _client(base, ADMIN), _client(base, THERAPIST), _client(base, PATIENT)
        pid = patient.get("/api/v1/users/me").json()["id"]
        device = {"Authorization": f"Bearer {_device_token(base, admin, pid)}",
                  "Content-Type": "application/octet-stream"}  # fmt: skip
        on_server, on_worker = ProcessMeter(server.pid), ProcessMeter(worker.pid)
        on_exporter = ProcessMeter(exporter.pid)

        def budget(kind: str) -> tuple[float, int]:
            return work_budget.budget(duration_s, kind)

        row, r = measure("POST /sessions (upload)", on_server, budget("upload"),
                         lambda: httpx.post(f"{base}/api/v1/sessions", params={"exercise": "squat"}, content=data,
                                            headers=device, timeout=1800))  # fmt: skip
        rows.append(row)
        print(row, flush=True)
        if r.status_code != 201:
            raise SystemExit(f"upload refused: {r.status_code} {r.text[:300]}")
        sid = r.json()["id"]
        s, p = f"/api/v1/sessions/{sid}", f"/api/v1/patients/{pid}"
        if not only or any("detail" in o for o in only):
            row, _ = measure(
                "detail build (worker job)", on_worker, budget("detail"), lambda: _detail_built(patient, sid)
            )
            rows.append(row)
            print(row, flush=True)
        small = prepared_export.in_request(duration_s=duration_s, n_frames=n_frames, max_s=settings.EXPORT_DIRECT_MAX_S,
                                           max_frames=settings.EXPORT_DIRECT_MAX_FRAMES)  # fmt: skip
        for fmt in [f for f in sf_formats() if not only or any(o in f"GET /export?format={f}" for o in only)]:
            path = f"{s}/export?format={fmt}"
            if small:  # built in the request, every time: held to the request's own bound
                rows.append(_repeated(f"GET /export?format={fmt} (in the request)", on_server,
                                      work_budget.EXPORT_IN_REQUEST, partial(patient.get, path),
                                      repeat))  # fmt: skip
                continue
            row, _ = measure(f"export?format={fmt} build (worker job)", on_exporter, budget("export"),
                             partial(_export_built, patient, path))  # fmt: skip
            rows.append(row)
            print(row, flush=True)
            rows.append(_repeated(f"GET /export?format={fmt} (stored)", on_server, budget("detail"),
                                  partial(patient.get, path), repeat))  # fmt: skip
        reads = [
            ("GET /sessions/{id}", patient, s, "detail"),
            ("GET /detail (stored)", patient, f"{s}/detail", "detail"),
            ("GET /file", patient, f"{s}/file", "detail"),
            ("GET /metric-versions", therapist, f"{s}/metric-versions", "detail"),
            ("GET /report.pdf", therapist, f"{p}/report.pdf", "detail"),
            ("GET /archive", patient, f"{p}/archive", "detail"),
        ]
        reads = [r for r in reads if not only or any(o in r[0] for o in only)]
        for name, client, path, kind in reads:
            row, _ = measure(name, on_server, budget(kind), partial(client.get, path))
            rows.append(row)
            print(row, flush=True)
        if only and not any("replay" in o for o in only):
            return rows
        for layer in ("raw", ""):
            what = "replay?layer=raw" if layer else "replay"
            row, _ = measure(f"{what} build (worker job)", on_worker, budget("replay"),
                             partial(_replay_built, patient, sid, layer))  # fmt: skip
            rows.append(row)
            print(row, flush=True)
            path = f"{s}/replay" + (f"?layer={layer}" if layer else "")
            row, _ = measure(f"GET /{what} (stored)", on_server, budget("detail"), partial(patient.get, path))
            rows.append(row)
            print(row, flush=True)
    finally:
        for process in (worker, exporter):
            process.terminate()
            process.wait(timeout=600)
        stop_server(server)
    return rows


def _repeated(endpoint: str, meter: ProcessMeter, budget: tuple[float, int], send: Callable[[], httpx.Response],
              repeat: int) -> Measured:  # fmt: skip
    """Returns the request measured `repeat` times: the median of its wall and CPU time, the largest peak (the first
    run's, usually: later ones reuse memory the process kept) and the worst status."""
    runs = [measure(endpoint, meter, budget, send)[0] for _ in range(repeat)]
    row = runs[-1]
    row.wall_s, row.cpu_s = (float(np.median([getattr(r, k) for r in runs])) for k in ("wall_s", "cpu_s"))
    row.peak_mib = max(r.peak_mib for r in runs)
    row.status = max(r.status for r in runs)
    print(row, f"(median of {repeat})" if repeat > 1 else "", flush=True)
    return row


def _export_built(client: httpx.Client, path: str) -> httpx.Response:
    """Asks for an export until it is something else than 202 (the first ask queues its build); returns that answer
    (the stored file read at the end is the server's, not the worker's, work)."""
    while True:
        r = client.get(path)
        if r.status_code != 202:
            return r
        time.sleep(0.5)


def sf_formats() -> tuple[str, ...]:
    """Returns the export formats the server offers."""
    from kinect_agent.export.files import FORMATS

    return FORMATS


def print_table(db: str, rows: list[Measured], info: dict[str, float]) -> None:
    """Prints one database's rows."""
    print(f"\nWorst accepted file, db {db}: {info['n_frames']} frames, {info['duration_s']:.0f} s, "
          f"{info['file_mib']:.1f} MiB")  # fmt: skip
    print(f"{'endpoint':<30}{'status':>7}{'answer MiB':>11}{'wall s':>8}{'CPU s':>8}{'budget':>8}{'MiB':>7}"
          f"{'budget':>8}")  # fmt: skip
    for r in rows:
        flag = "  OVER" if r.failures else ""
        print(f"{r.endpoint:<30}{r.status:>7}{r.answer_mib:>11.2f}{r.wall_s:>8.1f}{r.cpu_s:>8.1f}"
              f"{r.budget_cpu_s:>8.0f}{r.peak_mib:>7.0f}{r.budget_mib:>8.0f}{flag}")  # fmt: skip


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--db", action="append", default=[], help="PostgreSQL URL (name contains 'bench'); "
                        "may be repeated; 'sqlite' for a SQLite file (default: sqlite only)")  # fmt: skip
    parser.add_argument("--json", type=Path, help="also write the numbers to this JSON file")
    parser.add_argument("--cache", type=Path, default=Path(tempfile.gettempdir()) / "coach-worst-file.khs",
                        help="where the file is kept between runs (writing it costs minutes of xz)")  # fmt: skip
    parser.add_argument("--only", nargs="+", default=[], help="only the endpoints whose name contains one of these")
    parser.add_argument(
        "--at-export-limit",
        action="store_true",
        help="the longest recording whose exports are "
        "built in the request (COACH_EXPORT_DIRECT_MAX_FRAMES over _MAX_S) instead of the worst file",
    )
    parser.add_argument("--repeat", type=int, default=1, help="ask each export this many times (median; default 1)")
    args = parser.parse_args()
    settings = Settings()
    n_frames, duration_s = settings.SESSION_MAX_FRAMES, settings.SESSION_MAX_DURATION_S
    if args.at_export_limit:
        n_frames, duration_s = settings.EXPORT_DIRECT_MAX_FRAMES, settings.EXPORT_DIRECT_MAX_S
        args.cache = args.cache.with_name(f"coach-export-limit-{n_frames}-{duration_s:g}.khs")
    if not args.cache.exists():
        args.cache.write_bytes(worst_file(n_frames, duration_s * (n_frames - 1) / n_frames))
    data = args.cache.read_bytes()
    decoded = sf.decode(data, max_frames=n_frames, max_decoded_bytes=settings.SESSION_MAX_DECODED_BYTES)
    file_frames, file_duration_s = decoded.raw.n_frames, decoded.raw.duration
    info = {"n_frames": file_frames, "duration_s": file_duration_s, "file_mib": len(data) / 2**20}
    print(f"file: {info}", flush=True)
    databases: dict[str, list[dict[str, object]]] = {}
    report, failures = {"file": info, "databases": databases}, []
    with tempfile.TemporaryDirectory() as tmp:
        for db in args.db or ["sqlite"]:
            url = demo_clinic(None if db == "sqlite" else db, Path(tmp))
            label = "SQLite" if db == "sqlite" else "PostgreSQL"
            rows = run(url, data, file_duration_s, file_frames, args.only, args.repeat)
            print_table(label, rows, info)
            databases[label] = [asdict(r) for r in rows]
            failures += [f"{label}: {f}" for r in rows for f in r.failures]
    if args.json:
        args.json.write_text(json.dumps(report, indent=1))
    print("\n" + ("\n".join(failures) if failures else "every endpoint within its budget"))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
