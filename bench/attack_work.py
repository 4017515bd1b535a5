"""bench/attack.py's family "file chooses the work": accepted files whose content would set the server's work.

Each case is a valid session file that asks for more work than its recording is worth: a params["config"] with
large outlier_iterations or outlier_window_s, a high frame rate (1 kHz), the most frames the server accepts, or a
long duration. It is uploaded by a paired device, then GET /sessions/{id}/detail, /replay and /export?format=bvh are
sent once each (a worker prepares them: the answer is 202, or the export itself for a short recording), then a
real worker (backend.jobs.worker.work, in this process) builds what each queued, one kind of job at a time, and
each is read again (200 expected). For every request and build the CPU time of the process (time.process_time:
the app, the test client and the worker run in it, nothing else) and its peak resident memory above its start
(/proc/self/statm sampled every 2 ms) are measured and compared with the budget of backend.session_texts.work_budget:
BUDGETS[request] per started 10 minutes of recording (a stored read with the upload's). A case fails when a
request answers 5xx, stays 202 after its build, or exceeds its budget; a file the server refuses at upload (4xx)
passes, its refusal is the bound.
"""

from __future__ import annotations

import threading
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import httpx
import numpy as np

from backend.session_texts import work_budget
from kinect_agent.formats import session_file as sf
from kinect_agent.recording import Recording
from kinect_agent.sources.simulator import simulate

if TYPE_CHECKING:
    from fastapi.testclient import TestClient
    from sqlalchemy import Engine

    from backend.config import Settings

Sent = TypeVar("Sent")  # what a measured call returns: a response, or the number of jobs a worker ran

FAMILY = "file_chooses_work"
CREATED_AT = "2025-06-01T10:00:00Z"
_PAGE = 4096


@dataclass(frozen=True)
class WorkCase:
    """One accepted-looking file: a name saying what it asks for, and a callable making its bytes."""

    name: str
    make: Callable[[], bytes]


def _payload(raw: Recording, filtered: Recording | None, params: dict[str, Any]) -> bytes:
    return sf.encode(sf.SessionPayload(session_id=str(uuid.uuid4()), raw=raw, filtered=filtered, params=params,
                                       created_at=CREATED_AT))  # fmt: skip


def _tiled(rec: Recording, n: int, period_s: float) -> Recording:
    """Returns rec's frames repeated to n frames, period_s apart."""
    reps = -(-n // rec.n_frames)
    positions = np.tile(rec.positions, (reps, 1, 1))[:n]
    state = np.tile(rec.state, (reps, 1))[:n]
    return rec.replace(t=np.arange(n) * period_s, positions=positions, state=state)


def config_file(config: dict[str, Any], reps: int = 10) -> bytes:
    """Returns a simulated 30 Hz squat set of `reps` repetitions whose params["config"] is `config`."""
    measured, truth, _ = simulate("squat", reps, seed=11)
    return _payload(measured, truth, {"config": config})


def rate_file(n_frames: int, period_s: float) -> bytes:
    """Returns a squat recording of n_frames frames period_s apart (the simulator's frames repeated)."""
    measured, truth, _ = simulate("squat", 5, seed=12)
    return _payload(_tiled(measured, n_frames, period_s), _tiled(truth, n_frames, period_s), {})


def work_cases(max_frames: int, cache_dir: Path, quick: bool = False) -> list[WorkCase]:
    """Returns the family's cases (the largest files are cached in cache_dir)."""

    def cached(name: str, make: Callable[[], bytes]) -> Callable[[], bytes]:
        def load() -> bytes:
            path = cache_dir / f"coach-attack-work-{name}.khs"
            if not path.exists():
                path.write_bytes(make())
            return path.read_bytes()

        return load

    cases = [
        WorkCase("config outlier_iterations=200", lambda: config_file({"outlier_iterations": 200})),
        WorkCase("config outlier_window_s=100", lambda: config_file({"outlier_window_s": 100.0})),
        WorkCase(
            "config segment+excursions 1000 s",
            lambda: config_file({"outlier_segment": "or", "excursion_min_len_s": 0.01, "excursion_max_len_s": 1000.0}),
        ),  # fmt: skip
        WorkCase("rate 1 kHz, 3000 frames", lambda: rate_file(3000, 0.0010001)),
        WorkCase("rate 30 Hz, 10 min", cached("30hz-10min", lambda: rate_file(18_000, 1 / 30))),
    ]
    if not quick:
        cases += [
            WorkCase("config outlier_iterations=600", lambda: config_file({"outlier_iterations": 600})),
            WorkCase(
                f"rate 1 kHz, {max_frames} frames",
                cached(f"1khz-{max_frames}", lambda: rate_file(max_frames, 0.0010001)),
            ),  # fmt: skip
            WorkCase(
                f"duration 1 Hz, {max_frames} frames", cached(f"1hz-{max_frames}", lambda: rate_file(max_frames, 1.0))
            ),  # fmt: skip
        ]
    return cases


class PeakRss:
    """Samples this process's resident memory every 2 ms while active; peak_bytes: the peak above the start."""

    def __init__(self) -> None:
        self.start = self.peak = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    @staticmethod
    def rss() -> int:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * _PAGE

    def __enter__(self) -> PeakRss:
        self.start = self.peak = self.rss()
        self._thread = threading.Thread(target=self._sample, daemon=True)
        self._thread.start()
        return self

    def _sample(self) -> None:
        while not self._stop.wait(0.002):
            self.peak = max(self.peak, self.rss())

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        self.peak = max(self.peak, self.rss())

    @property
    def peak_bytes(self) -> int:
        return self.peak - self.start


def _measured(send: Callable[[], Sent]) -> tuple[Sent, float, float, int]:
    """Returns (response, wall s, CPU s, peak bytes) of one request."""
    wall, cpu = time.perf_counter(), time.process_time()
    with PeakRss() as rss:
        response = send()
    return response, time.perf_counter() - wall, time.process_time() - cpu, rss.peak_bytes


def jobs_runner(engine: Engine, settings: Settings) -> Callable[[str], int]:
    """Returns run(kind): a real worker (backend.jobs.worker.work) on engine runs every due job of that kind in this
    process (so _measured counts its CPU and memory) until none is left; returns how many it ran."""
    from sqlalchemy.orm import sessionmaker

    from backend.jobs.worker import work

    sessions = sessionmaker(bind=engine, expire_on_commit=False)

    def run(kind: str) -> int:
        return work(sessionmaker=sessions, settings=settings, name="bench-attack", once=True, kinds=(kind,))

    return run


EXPORT_FORMAT = "bvh"  # the dearest export of the worst file (bench/README.md)
# (request, path under the session, the worker's job kind that builds it, the budget it is held to)
READS = (("detail", "detail", "detail"), ("replay", "replay", "replay"),
         ("export", f"export?format={EXPORT_FORMAT}", "export"))  # fmt: skip


def run_work_case(
    client: TestClient, case: WorkCase, headers: dict[str, str], reader: dict[str, str], run_jobs: Callable[[str], int]
) -> dict[str, Any]:
    """Uploads the case's file with a device's headers, asks for its detail, replay and BVH export with the patient's
    (reader) headers (202 while a worker prepares them, or the answer itself), then has a worker build each (run_jobs,
    one kind at a time) and reads each again (200 expected); returns the record: each request's and each build's
    status, wall and CPU seconds, peak bytes, budget and failures."""
    data = case.make()
    payload = sf.decode(data, max_frames=10**7, max_decoded_bytes=2**31)
    duration = payload.raw.duration
    requests: list[dict[str, Any]] = []
    failures: list[str] = []
    record = {"family": FAMILY, "name": case.name, "file_bytes": len(data), "n_frames": payload.raw.n_frames,
              "duration_s": round(duration, 1), "requests": requests, "failures": failures}  # fmt: skip

    def measured(name: str, kind: str, send: Callable[[], Sent], status_of: Callable[[Sent], int] = _status) -> Sent:
        response, wall, cpu, peak = _measured(send)
        cpu_budget, bytes_budget = work_budget.budget(duration, kind)
        status = status_of(response)
        requests.append(_request(name, response, status, wall, cpu, peak) | {"budget_cpu_s": cpu_budget,
                        "budget_mib": bytes_budget / 2**20})  # fmt: skip
        if status >= 500:
            failures.append(f"{name} {status}")
        if cpu > cpu_budget:
            failures.append(f"{name} {cpu:.2f} s CPU > {cpu_budget:g} s")
        if peak > bytes_budget:
            failures.append(f"{name} {peak / 2**20:.0f} MiB > {bytes_budget / 2**20:.0f} MiB")
        return response

    upload = measured("upload", "upload", lambda: client.post("/api/v1/sessions", content=data, headers=headers,
                                                               params={"exercise": "squat"}))  # fmt: skip
    if upload.status_code != 201:
        return record
    base = f"/api/v1/sessions/{upload.json()['id']}"
    for name, path, kind in READS:  # the request: queues the build (202), or answers
        measured(name, kind, partial(client.get, f"{base}/{path}", headers=reader))
    for name, path, kind in READS:  # the worker's build: what the 202 put off
        measured(f"{name} build", kind, partial(run_jobs, kind), status_of=_built)
        again = measured(f"{name} stored", "upload", partial(client.get, f"{base}/{path}", headers=reader))
        if again.status_code != 200:
            failures.append(f"{name} still {again.status_code} after the worker ran")
    return record


def _status(response: Sent) -> int:
    """Returns the status code of a response (the default status of a measured request)."""
    if not isinstance(response, httpx.Response):
        raise TypeError(f"expected a response, got {type(response).__name__}")
    return response.status_code


def _built(ran: int) -> int:
    """Returns the status of a worker's build: 200 (how many jobs it ran is not its status)."""
    return 200


def _request(name: str, response: object, status: int, wall: float, cpu: float, peak: int) -> dict[str, Any]:
    error = ""
    if status >= 400 and isinstance(response, httpx.Response):
        try:
            error = f"{response.json().get('error')}: {str(response.json().get('detail'))[:120]}"
        except ValueError:
            error = response.text[:120]
    return {"request": name, "status": status, "wall_s": round(wall, 3), "cpu_s": round(cpu, 3),
            "peak_mib": round(peak / 2**20, 1), "error": error}  # fmt: skip


def print_work(db: str, records: list[dict[str, Any]]) -> None:
    """Prints the family's table for one database."""
    budgets = ", ".join(f"{k} {c:g} s, {m / 2**20:.0f} MiB" for k, (c, m) in work_budget.BUDGETS.items())
    print(f"\nFile chooses the work, db {db}: budget per started 10 min of recording: {budgets}")
    print(f"{'case':<38}{'frames':>8}{'dur s':>9}  {'request':<15}{'status':>7}{'wall s':>8}{'CPU s':>8}{'MiB':>7}")
    for r in records:
        for i, q in enumerate(r["requests"]):
            head = f"{r['name']:<38}{r['n_frames']:>8}{r['duration_s']:>9}" if i == 0 else " " * 55
            print(f"{head}  {q['request']:<15}{q['status']:>7}{q['wall_s']:>8.2f}{q['cpu_s']:>8.2f}"
                  f"{q['peak_mib']:>7.0f}  {q['error']}")  # fmt: skip
        if r["failures"]:
            print(f"  FAILED: {'; '.join(r['failures'])}")
