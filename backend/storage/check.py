"""`coach-server storage check|move-out|move-in|init`: the object store seen from the database, and the moves."""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass, field

import sqlalchemy as sa
from sqlalchemy.engine import Connection

from backend.storage.base import ObjectStore
from backend.storage.errors import StorageError

_SESSION = sa.table("exercise_session", sa.column("id"), sa.column("file_key"), sa.column("content_hash"),
                    sa.column("file_bytes"))  # fmt: skip
_REPLAY = sa.table("session_replay", sa.column("id"), sa.column("session_id"), sa.column("data_key"),
                   sa.column("data_hash"))  # fmt: skip
_DETAIL = sa.table("session_detail", sa.column("id"), sa.column("session_id"), sa.column("data_key"),
                   sa.column("data_hash"))  # fmt: skip
_EARLIER = sa.table("session_metric_version", sa.column("id"), sa.column("session_id"), sa.column("file_key"),
                    sa.column("file_hash"))  # fmt: skip
_ARCHIVE = sa.table("patient_archive", sa.column("id"), sa.column("patient_id"), sa.column("data_key"),
                    sa.column("data_hash"))  # fmt: skip
_EXPORT = sa.table("session_export", sa.column("id"), sa.column("session_id"), sa.column("format"),
                   sa.column("data_key"), sa.column("data_hash"))  # fmt: skip


@dataclass
class CheckReport:
    """Rows whose object is missing or corrupt, objects no row points to, and counts."""

    checked: int = 0
    in_database: int = 0  # session files still held as database blobs (not moved out yet)
    missing: list[str] = field(default_factory=list)  # "session 12: session/ab/…"
    corrupt: list[str] = field(default_factory=list)
    orphans: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """Returns whether every row's object is present and intact."""
        return not self.missing and not self.corrupt


def check(conn: Connection, store: ObjectStore) -> CheckReport:
    """Reads every object a row points to (checking its sha256) and lists the store's keys no row points to."""
    report = CheckReport()
    referenced: set[str] = set()
    rows = conn.execute(sa.select(_SESSION.c.id, _SESSION.c.file_key, _SESSION.c.content_hash)
                        .where(_SESSION.c.file_key.is_not(None)).order_by(_SESSION.c.id))  # fmt: skip
    targets = [(f"session {r.id}", r.file_key, r.content_hash) for r in rows]
    rows = conn.execute(sa.select(_REPLAY.c.session_id, _REPLAY.c.data_key, _REPLAY.c.data_hash)
                        .where(_REPLAY.c.data_key.is_not(None)).order_by(_REPLAY.c.id))  # fmt: skip
    targets += [(f"replay of session {r.session_id}", r.data_key, r.data_hash) for r in rows]
    rows = conn.execute(sa.select(_DETAIL.c.session_id, _DETAIL.c.data_key, _DETAIL.c.data_hash)
                        .order_by(_DETAIL.c.id))  # fmt: skip
    targets += [(f"detail of session {r.session_id}", r.data_key, r.data_hash) for r in rows]
    rows = conn.execute(sa.select(_EXPORT.c.session_id, _EXPORT.c.format, _EXPORT.c.data_key, _EXPORT.c.data_hash)
                        .order_by(_EXPORT.c.id))  # fmt: skip
    targets += [(f"{r.format} export of session {r.session_id}", r.data_key, r.data_hash) for r in rows]
    rows = conn.execute(sa.select(_ARCHIVE.c.patient_id, _ARCHIVE.c.data_key, _ARCHIVE.c.data_hash)
                        .order_by(_ARCHIVE.c.id))  # fmt: skip
    targets += [(f"archive of patient {r.patient_id}", r.data_key, r.data_hash) for r in rows]
    targets += _earlier_files(conn, current={key for _, key, _ in targets})
    for what, key, digest in targets:
        referenced.add(key)
        report.checked += 1
        problem = store.check(key, digest)
        if problem == "missing":
            report.missing.append(f"{what}: {key}")
        elif problem == "corrupt":
            report.corrupt.append(f"{what}: {key}")
    report.in_database = (
        conn.scalar(sa.select(sa.func.count()).select_from(_SESSION).where(_SESSION.c.file_bytes.is_not(None))) or 0
    )
    report.orphans = sorted(k for k in store.keys() if k not in referenced)
    return report


def _earlier_files(conn: Connection, *, current: set[str]) -> list[tuple[str, str, str]]:
    """Returns (what, key, sha256) of the session files a re-analysis with the pipeline replaced (named beside the
    metrics they gave in session_metric_version), each once, leaving out keys in `current` (checked already)."""
    rows = conn.execute(sa.select(_EARLIER.c.session_id, _EARLIER.c.file_key, _EARLIER.c.file_hash)
                        .where(_EARLIER.c.file_key.is_not(None)).order_by(_EARLIER.c.id))  # fmt: skip
    found: dict[str, tuple[str, str, str]] = {}
    for r in rows:
        if r.file_key not in current:
            found.setdefault(r.file_key, (f"earlier file of session {r.session_id}", r.file_key, r.file_hash))
    return list(found.values())


def run(args: argparse.Namespace) -> int:
    """Runs one storage subcommand; returns the exit status (1 when check finds a missing or corrupt object)."""
    from backend.database import get_engine
    from backend.storage.factory import get_store
    from backend.storage.move import move_in, move_out

    store = get_store()
    try:
        if args.action == "init":
            if hasattr(store, "ensure_bucket"):
                store.ensure_bucket()
            print(f"object store ready: {store.describe()}")
            return 0
        with get_engine().connect() as conn:
            if args.action == "check":
                report = check(conn, store)
                print(f"{store.describe()}: {report.checked} object(s) checked, {len(report.missing)} missing, "
                      f"{len(report.corrupt)} corrupt, {len(report.orphans)} not referenced by any row, "
                      f"{report.in_database} session file(s) still in the database")  # fmt: skip
                for line in report.missing:
                    print(f"missing  {line}")
                for line in report.corrupt:
                    print(f"corrupt  {line}")
                if args.orphans:
                    for key in report.orphans:
                        print(f"orphan   {key}")
                return 0 if report.ok else 1
            mover = move_out if args.action == "move-out" else move_in
            moved = mover(conn, store, batch=args.batch, commit=True, progress=lambda m: print(m, file=sys.stderr))
            conn.commit()
            print(f"{store.describe()}: {moved.text()}")
            return 0
    except StorageError as exc:
        print(f"coach-server: storage error: {exc.message}", file=sys.stderr)
        return 1


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Adds the storage subcommand's arguments."""
    p.add_argument("action", choices=("check", "move-out", "move-in", "init"),
                   help="check: read every stored object against its sha256 (exit 1 on a missing or corrupt one); "
                        "move-out / move-in: move files between database blobs and the store, one committed batch "
                        "at a time (resumable); init: create the bucket when missing")  # fmt: skip
    p.add_argument("--batch", type=int, default=100, help="rows per committed batch of a move (default 100)")
    p.add_argument("--orphans", action="store_true", help="check: list the objects no row points to")
