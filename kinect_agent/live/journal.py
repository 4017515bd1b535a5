"""The frames of the set being recorded, appended to disk as they come, so a crash keeps what was recorded.

    <folder>/<session id>.json     header: session id, start time (created_at), metadata
    <folder>/<session id>.frames   fixed-size records (RECORD): t, positions (J, 3) m camera frame, state (J,)

Records are flushed and fsynced every FLUSH_S seconds, so a crash loses at most that much. After a crash the
next start of the agent calls `recover`: a set with at least MIN_KEEP_S seconds of frames is kept (queued like
any finished set, with meta.extra["interrupted"] = True); a shorter fragment is dropped.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from kinect_agent import skeleton
from kinect_agent.config import fsync_dir
from kinect_agent.queue import check_session_id
from kinect_agent.recording import Metadata, Recording

RECORD = np.dtype([("t", "<f8"), ("positions", "<f8", (skeleton.J, 3)), ("state", "i1", (skeleton.J,))])
FLUSH_S = 0.5
MIN_KEEP_S = 5.0


@dataclass
class Interrupted:
    """A set found on disk at start-up: its recording (None when too short or unreadable) and header."""

    session_id: str
    created_at: str
    recording: Recording | None
    reason: str = ""


class Journal:
    """Appends one set's frames to <folder>/<session id>.frames; `finish` returns them as a Recording."""

    def __init__(self, folder: str | Path, session_id: str, meta: Metadata, created_at: str) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.session_id = check_session_id(session_id)
        self.meta = meta
        header = {"session_id": session_id, "created_at": created_at, "meta": meta.to_dict()}
        self.header_path.write_text(json.dumps(header))
        self._file = open(self.frames_path, "ab")  # noqa: SIM115 - closed in finish/discard
        fsync_dir(self.folder)
        self._buffer: list[bytes] = []
        self._flushed = time.monotonic()
        self.n_frames = 0

    @property
    def header_path(self) -> Path:
        return self.folder / f"{self.session_id}.json"

    @property
    def frames_path(self) -> Path:
        return self.folder / f"{self.session_id}.frames"

    def append(self, t: float, positions: np.ndarray, state: np.ndarray) -> None:
        """Adds one frame: t s, positions (J, 3) m camera frame (NaN = untracked), state (J,) 0/1/2."""
        rec = np.zeros((), RECORD)
        rec["t"], rec["positions"], rec["state"] = t, positions, state
        self._buffer.append(rec.tobytes())
        self.n_frames += 1
        if time.monotonic() - self._flushed >= FLUSH_S:
            self.flush()

    def flush(self) -> None:
        """Writes the buffered frames and fsyncs them."""
        if self._buffer:
            self._file.write(b"".join(self._buffer))
            self._buffer.clear()
            self._file.flush()
            os.fsync(self._file.fileno())
        self._flushed = time.monotonic()

    def finish(self) -> Recording | None:
        """Closes the journal and returns its frames as a Recording (None without frames); the files stay until
        `discard` (call it once the set is safely queued)."""
        self.flush()
        self._file.close()
        return read_frames(self.frames_path, self.meta)

    def discard(self) -> None:
        """Removes the journal's files."""
        if not self._file.closed:
            self._file.close()
        for path in (self.frames_path, self.header_path):
            path.unlink(missing_ok=True)
        fsync_dir(self.folder)


def read_frames(path: Path, meta: Metadata) -> Recording | None:
    """Returns the whole records of a frames file as a Recording (a torn last record is ignored), None if empty.

    Frames whose time does not increase (a corrupt record) end the recording there.
    """
    data = path.read_bytes()
    n = len(data) // RECORD.itemsize
    if n == 0:
        return None
    rec = np.frombuffer(data[: n * RECORD.itemsize], dtype=RECORD)
    t = rec["t"]
    bad = np.flatnonzero(~np.isfinite(t[1:]) | (np.diff(t) <= 0))
    keep = int(bad[0]) + 1 if bad.size else n
    state = np.where(np.all(np.isfinite(rec["positions"][:keep]), axis=-1), rec["state"][:keep], 0)
    return Recording(t[:keep].copy(), rec["positions"][:keep].copy(), state.astype(np.int8), meta)


def recover(folder: str | Path) -> list[Interrupted]:
    """Returns the sets left on disk by a crash and removes their files (queue the kept ones first: see serve)."""
    folder = Path(folder)
    found = []
    for header_path in sorted(folder.glob("*.json")) if folder.is_dir() else []:
        frames_path = header_path.with_suffix(".frames")
        try:
            header = json.loads(header_path.read_text())
            meta = Metadata.from_dict(header["meta"])
            meta.extra["interrupted"] = True
            rec = read_frames(frames_path, meta) if frames_path.exists() else None
            reason = "" if rec is not None and rec.duration >= MIN_KEEP_S else f"shorter than {MIN_KEEP_S:g} s"
            found.append(Interrupted(header["session_id"], header["created_at"], None if reason else rec, reason))
        except (OSError, ValueError, KeyError, TypeError) as exc:
            found.append(Interrupted(header_path.stem, "", None, f"unreadable: {exc}"))
    return found


def remove(folder: str | Path, session_id: str) -> None:
    """Removes the files of one journal."""
    folder = Path(folder)
    for suffix in (".frames", ".json"):
        (folder / f"{session_id}{suffix}").unlink(missing_ok=True)
    fsync_dir(folder)
