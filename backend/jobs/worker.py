"""`coach-server worker`: takes jobs from the queue (re-analysis, replay builds, session details, long sessions'
exports, patients' archives, ending abandoned camera sets) and runs them, one at a time, until stopped (or --once);
EmbeddedWorker runs the same loop in a thread of a server process (COACH_EMBEDDED_WORKER). Every
COACH_CAMERA_SWEEP_S (and when it starts) the loop also queues the end of camera sets idle for
COACH_CAMERA_SET_IDLE_HOURS (backend.camera.sweep)."""

from __future__ import annotations

import argparse
import logging
import os
import signal
import socket
import sys
import threading
import time
import traceback
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from backend.jobs import queue
from backend.jobs.errors import PermanentJobError
from backend.jobs.models import Job

if TYPE_CHECKING:
    from backend.config import Settings

KINDS = ("reanalyze", "replay", "detail", "export", "archive", "camera_end")

log = logging.getLogger(__name__)


def run_job(db_session: Session, job: Job, settings: Settings) -> dict[str, Any]:
    """Runs one job and returns its result (raises on failure)."""
    if job.kind == "reanalyze":
        from backend.records.reanalysis import reanalyze_session

        return reanalyze_session(db_session=db_session, session_id=int(job.payload["session_id"]),
                                 max_frames=settings.SESSION_MAX_FRAMES,
                                 max_decoded_bytes=settings.SESSION_MAX_DECODED_BYTES,
                                 pipeline=bool(job.payload.get("pipeline", False)))  # fmt: skip
    if job.kind == "replay":
        from backend.replay import jobs, scene

        return jobs.run(db_session=db_session, session_id=int(job.payload["session_id"]),
                        max_frames=settings.SESSION_MAX_FRAMES, max_decoded_bytes=settings.SESSION_MAX_DECODED_BYTES,
                        layers=tuple(job.payload.get("layers") or scene.LAYERS))  # fmt: skip
    if job.kind == "detail":
        from backend.sessions import prepared

        return prepared.run(db_session=db_session, session_id=int(job.payload["session_id"]),
                            max_frames=settings.SESSION_MAX_FRAMES,
                            max_decoded_bytes=settings.SESSION_MAX_DECODED_BYTES)  # fmt: skip
    if job.kind == "export":
        from backend.sessions import prepared_export

        return prepared_export.run(db_session=db_session, session_id=int(job.payload["session_id"]),
                                   fmt=str(job.payload["format"]), max_frames=settings.SESSION_MAX_FRAMES,
                                   max_decoded_bytes=settings.SESSION_MAX_DECODED_BYTES)  # fmt: skip
    if job.kind == "archive":
        from backend.records import prepared_archive

        return prepared_archive.run(db_session=db_session, patient_id=int(job.payload["patient_id"]),
                                    requested_by=str(job.payload.get("requested_by") or "the patient"),
                                    settings=settings, job_id=job.id)  # fmt: skip
    if job.kind == "camera_end":
        import uuid

        from backend.camera.sweep import end_idle_set

        return end_idle_set(db_session=db_session, set_id=uuid.UUID(job.payload["set_id"]),
                            idle_hours=settings.CAMERA_SET_IDLE_HOURS, max_frames=settings.SESSION_MAX_FRAMES,
                            max_decoded_bytes=settings.SESSION_MAX_DECODED_BYTES)  # fmt: skip
    raise ValueError(f"unknown job kind {job.kind!r}")


def queue_periodic(*, sessionmaker: Callable[[], Session], settings: Settings) -> int:
    """Queues the periodic work (the end of abandoned camera sets) and commits; returns how many jobs were added.
    A database fault is logged, not raised: the loop goes on with the jobs already queued."""
    from backend.camera.sweep import queue_idle_sets

    try:
        with sessionmaker() as db_session:
            added = queue_idle_sets(db_session=db_session, idle_hours=settings.CAMERA_SET_IDLE_HOURS)
            db_session.commit()
            return added
    except Exception:  # noqa: BLE001 - the next sweep tries again
        log.exception("looking for abandoned camera sets failed; trying again in %s s", settings.CAMERA_SWEEP_S)
        return 0


def work(
    *,
    sessionmaker: Callable[[], Session],
    settings: Settings,
    name: str,
    once: bool = False,
    idle_s: float = 1.0,
    stop: Callable[[], bool] = lambda: False,
    kinds: tuple[str, ...] = KINDS,
) -> int:
    """Runs jobs of `kinds` until stop() (or, once=True, until none is due); returns how many it ran. The periodic
    work is queued first and then every settings.CAMERA_SWEEP_S."""
    ran, next_sweep = 0, 0.0
    while not stop():
        if time.monotonic() >= next_sweep:
            queue_periodic(sessionmaker=sessionmaker, settings=settings)
            next_sweep = time.monotonic() + settings.CAMERA_SWEEP_S
        with sessionmaker() as db_session:
            job = queue.claim(db_session=db_session, worker=name, kinds=kinds)
            if job is None:
                if once:
                    return ran
                time.sleep(idle_s)
                continue
            run_claimed(db_session, job, settings)
            ran += 1
    return ran


def run_claimed(db_session: Session, job: Job, settings: Settings) -> Job:
    """Runs a job this process claimed and marks it done, committing its work with it; or, when it raises, rolls
    its work back and marks it failed (queued again while it has tries left). Returns the job."""
    try:
        result = run_job(db_session, job, settings)
    except Exception as exc:  # noqa: BLE001 - any failure is retried, then recorded on the job
        db_session.rollback()
        job = db_session.merge(job)
        queue.fail(db_session=db_session, job=job, error=f"{type(exc).__name__}: {exc}\n"
                   f"{traceback.format_exc(limit=3)}", final=isinstance(exc, PermanentJobError))  # fmt: skip
    else:
        queue.finish(db_session=db_session, job=job, result=result)  # commits the work with the job
    return job


def run_here_or_wait(
    *, db_session: Session, key: str, settings: Settings, name: str, poll_s: float = 0.5
) -> Job | None:
    """Runs the queued job `key` in this process, or waits while a worker runs it, until it is done or failed for
    good; returns it then (None when it is gone: erased meanwhile). For a command that wants a job's result now
    without doing the work a second time: it claims the job as a worker would (queue.claim_key), so a worker and
    the command never both run it. A job queued again after a failure (its retry delay) is waited for, then run."""
    while True:
        job = queue.claim_key(db_session=db_session, key=key, worker=name)
        if job is not None:
            job = run_claimed(db_session, job, settings)
            if job.status != "queued":
                return job
            continue
        db_session.expire_all()
        job = db_session.scalar(select(Job).where(Job.key == key))
        db_session.commit()  # no snapshot held while waiting
        if job is None or job.status in ("done", "failed"):
            return job
        time.sleep(poll_s)


class EmbeddedWorker:
    """The worker loop in a daemon thread of a server process (the demo, a one-process install); stop() ends it
    after the job in hand."""

    def __init__(self, *, sessionmaker: Callable[[], Session], settings: Settings) -> None:
        self._stopping = threading.Event()
        self.name = f"{socket.gethostname()}:{os.getpid()}:embedded"
        self._thread = threading.Thread(
            target=work,
            kwargs={"sessionmaker": sessionmaker, "settings": settings, "name": self.name, "idle_s": 0.5,
                    "stop": self._stopping.is_set},
            name="coach-embedded-worker",
            daemon=True,
        )  # fmt: skip

    def start(self) -> EmbeddedWorker:
        """Starts the thread; returns self."""
        self._thread.start()
        return self

    def stop(self, timeout_s: float = 5.0) -> None:
        """Asks the loop to stop and waits up to timeout_s for the job in hand."""
        self._stopping.set()
        self._thread.join(timeout_s)


def main(args: argparse.Namespace) -> int:
    """Runs the worker until SIGTERM/SIGINT (the job in hand is finished first)."""
    from backend.config import get_settings
    from backend.database import get_sessionmaker, import_all_models
    from kinect_agent.blas_threads import one_blas_thread

    one_blas_thread()  # as every server process (backend.main): small matrices, and BLAS threads spin on shared cores
    import_all_models()  # the job's queries join across every table's foreign keys
    stopping = []
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stopping.append(True))
    name = f"{socket.gethostname()}:{os.getpid()}"
    kinds = tuple(getattr(args, "kinds", None) or KINDS)
    print(f"worker {name} started ({', '.join(kinds)})", file=sys.stderr)
    ran = work(sessionmaker=get_sessionmaker(), settings=get_settings(), name=name, once=args.once,
               stop=lambda: bool(stopping), kinds=kinds)  # fmt: skip
    print(f"worker {name} stopped after {ran} job(s)", file=sys.stderr)
    return 0
