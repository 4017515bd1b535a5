"""Enqueue, claim, finish and retry jobs (backend.jobs.models.Job); see the package doc for the design."""

from __future__ import annotations

import datetime as dt
from collections.abc import Callable, Iterable
from typing import Any, cast

from sqlalchemy import and_, func, or_, select, update
from sqlalchemy.dialects.postgresql import Insert as PgInsert
from sqlalchemy.dialects.postgresql import insert as pg_insert
from sqlalchemy.dialects.sqlite import Insert as SqliteInsert
from sqlalchemy.dialects.sqlite import insert as sqlite_insert
from sqlalchemy.engine import CursorResult
from sqlalchemy.orm import Session
from sqlalchemy.sql import ColumnElement

from backend.database import utcnow
from backend.jobs.models import MAX_ATTEMPTS, Job

LEASE = dt.timedelta(minutes=5)
CHUNK = 1000  # jobs per INSERT statement
RETRY_DELAYS_S = (5.0, 30.0, 120.0)


def enqueue(
    *,
    db_session: Session,
    kind: str,
    items: Iterable[tuple[str, dict[str, Any]]],
    batch: str | None = None,
    retry_failed: bool = False,
) -> int:
    """Adds one job per (key, payload) whose key is not queued yet; returns how many were added. Flushes.

    One multi-row INSERT ... ON CONFLICT (key) DO NOTHING per CHUNK items (PostgreSQL and SQLite both have it), so
    10 000 sessions queue in one round trip per thousand and concurrent requests for the same key add one job.
    retry_failed: a job of the same key that ended `failed` is queued again in this batch with fresh tries (and
    counted as added), e.g. a re-analysis asked again after the missing file was restored; done, queued and running
    jobs are left as they are.
    """
    db_session.flush()
    insert = pg_insert if db_session.get_bind().dialect.name == "postgresql" else sqlite_insert
    added, now, chunk = 0, utcnow(), []
    for key, payload in items:
        chunk.append({"kind": kind, "key": key, "batch": batch, "payload": payload, "status": "queued", "attempts": 0,
                      "max_attempts": MAX_ATTEMPTS, "run_after": now, "created_at": now})  # fmt: skip
        if len(chunk) == CHUNK:
            added += _insert_new(db_session, insert, chunk, retry_failed)
            chunk = []
    if chunk:
        added += _insert_new(db_session, insert, chunk, retry_failed)
    return added


def _insert_new(
    db_session: Session,
    insert: Callable[[type[Job]], PgInsert | SqliteInsert],
    rows: list[dict[str, Any]],
    retry_failed: bool,
) -> int:
    statement = insert(Job).values(rows)
    if retry_failed:
        new = statement.excluded
        statement = statement.on_conflict_do_update(
            index_elements=["key"],
            set_={"status": "queued", "batch": new.batch, "attempts": 0, "run_after": new.run_after, "error": None,
                  "result": None, "finished_at": None, "locked_by": None, "locked_until": None},
            where=Job.status == "failed",
        )  # fmt: skip
    else:
        statement = statement.on_conflict_do_nothing(index_elements=["key"])
    return len(db_session.execute(statement.returning(Job.id)).all())  # only inserted (or re-queued) rows come back


def _claimable(now: dt.datetime) -> ColumnElement[bool]:
    return or_(
        and_(Job.status == "queued", Job.run_after <= now),
        and_(Job.status == "running", Job.locked_until < now),  # its worker died: the lease expired
    )


def claim(*, db_session: Session, worker: str, kinds: tuple[str, ...], now: dt.datetime | None = None) -> Job | None:
    """Takes the oldest job that is due (or whose lease expired) for `worker` and commits; None when none is."""
    for _ in range(5):  # another worker may take the candidate first
        now = now or utcnow()
        query = select(Job.id).where(Job.kind.in_(kinds), _claimable(now)).order_by(Job.id).limit(1)
        if db_session.get_bind().dialect.name == "postgresql":
            query = query.with_for_update(skip_locked=True)
        job_id = db_session.scalar(query)
        if job_id is None:
            db_session.commit()
            return None
        if _take(db_session, Job.id == job_id, worker, now):
            return db_session.get(Job, job_id)
        now = None
    return None


def claim_key(*, db_session: Session, key: str, worker: str, now: dt.datetime | None = None) -> Job | None:
    """Takes the job `key` for `worker` when it is due (or its lease expired) and commits; None when it is not (no
    such job, not due, done, failed, or another worker holds it). One UPDATE whose WHERE says claimable: of two
    claims at once (workers, or a command that runs the job itself) exactly one takes it, as with claim."""
    now = now or utcnow()
    taken = _take(db_session, Job.key == key, worker, now)
    return db_session.scalar(select(Job).where(Job.key == key)) if taken else None


def _take(db_session: Session, which: ColumnElement[bool], worker: str, now: dt.datetime) -> bool:
    """Marks the claimable job `which` selects running for `worker` (leased until now + LEASE) and commits; returns
    whether it did (another worker may have taken it first)."""
    done = db_session.execute(
        update(Job)
        .where(which, _claimable(now))
        .values(status="running", locked_by=worker, locked_until=now + LEASE, attempts=Job.attempts + 1)
    )
    taken = cast("CursorResult[Any]", done).rowcount  # an UPDATE's result is a CursorResult
    db_session.commit()
    return bool(taken)


def finish(*, db_session: Session, job: Job, result: dict[str, Any]) -> None:
    """Marks a job done with its result and commits."""
    job.status, job.result, job.error = "done", result, None
    job.locked_by = job.locked_until = None
    job.finished_at = utcnow()
    db_session.commit()


def fail(*, db_session: Session, job: Job, error: str, final: bool = False) -> None:
    """Queues the job again after a delay, or marks it failed after max_attempts (at once when final: a retry
    cannot succeed); commits."""
    job.error = error[:4000]
    job.locked_by = job.locked_until = None
    if final or job.attempts >= job.max_attempts:
        job.status, job.finished_at = "failed", utcnow()
    else:
        job.status = "queued"
        job.run_after = utcnow() + dt.timedelta(seconds=RETRY_DELAYS_S[min(job.attempts, len(RETRY_DELAYS_S)) - 1])
    db_session.commit()


def progress(*, db_session: Session, batch: str) -> dict[str, int]:
    """Returns {"queued", "running", "done", "failed", "total"} counts of a batch."""
    counts = dict(
        db_session.execute(select(Job.status, func.count()).where(Job.batch == batch).group_by(Job.status)).all()
    )
    out = {s: int(counts.get(s, 0)) for s in ("queued", "running", "done", "failed")}
    out["total"] = sum(out.values())
    return out
