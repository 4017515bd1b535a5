"""Capturing one set and queueing it, as a library: the `run` and `serve` commands and the server's demo clinic
(through kinect_agent.home) call these, none of them through another's command module.

capture(source, exercise=...)  -> the raw Recording of one set (simulator | replay FILE | kinect2 | azure |
                                   webcam [camera N] [VIDEO])
queue_session(queue, rec)      -> held raw in queue/captured/, filtered (make_payload), queued in queue/pending/
"""

from __future__ import annotations

import logging
import re
import uuid
from collections.abc import Callable
from datetime import UTC, datetime, timedelta
from pathlib import Path

from kinect_agent import formats
from kinect_agent.disk_full import is_disk_full, plain_words, write_when_space
from kinect_agent.errors import FormatError
from kinect_agent.formats.session_file import SessionPayload, as_stored
from kinect_agent.processing.config import PipelineConfig, config_for_device
from kinect_agent.processing.errors import ProcessingError
from kinect_agent.processing.pipeline import process
from kinect_agent.processing.provenance import pipeline_params
from kinect_agent.queue import SessionQueue
from kinect_agent.recording import Recording

log = logging.getLogger(__name__)

SOURCE_NAMES = {
    "simulator": "simulator",
    "replay": "replay",
    "kinect2": "kinect_v2",
    "kinect_v2": "kinect_v2",
    "azure": "azure_kinect",
    "azure_kinect": "azure_kinect",
    "webcam": "webcam",
}
_SLUG = re.compile(r"^[a-z0-9][a-z0-9_]{0,63}$")


def check_exercise(exercise: str) -> str:
    """Returns the slug if it looks like one (lower-case letters, digits, _); else raises ValueError."""
    if not isinstance(exercise, str) or not _SLUG.match(exercise):
        raise ValueError(f"--exercise {exercise!r} must be an exercise slug such as shoulder_abduction")
    return exercise


def check_source_file(kind: str, file: Path | None) -> None:
    """Raises ValueError unless a FILE is given exactly where needed (replay), or allowed (a webcam's video)."""
    if kind == "replay" and file is None:
        raise ValueError("a FILE is needed with --source replay")
    if kind not in ("replay", "webcam") and file is not None:
        raise ValueError("a FILE is only for --source replay (a recording) or --source webcam (a video)")


def capture(
    source: str,
    *,
    exercise: str,
    file: Path | None = None,
    reps: int = 10,
    seconds: float = 60.0,
    seed: int = 0,
    camera: int | None = None,
    model: str | None = None,
) -> Recording:
    """Returns the raw recording of one session from `source` (a key of SOURCE_NAMES), meta.exercise set."""
    check_exercise(exercise)
    kind = SOURCE_NAMES.get(source)
    if kind is None:
        raise ValueError(f"unknown source {source!r}; known sources: {', '.join(sorted(SOURCE_NAMES))}")
    check_source_file(kind, file)
    if kind == "simulator":
        from kinect_agent.sources.simulator import simulate

        rec = simulate(exercise, reps, seed=seed)[0]
    elif kind == "replay":
        assert file is not None  # checked above
        rec = formats.read(file)
    else:
        from kinect_agent.sources import make_source, record

        if not 0 < seconds <= 3600:
            raise ValueError(f"--seconds must be between 0 and 3600, got {seconds}")
        rec = record(make_source(kind, file=file, camera=camera, model=model), seconds)
    rec.meta.exercise = exercise
    return rec


def make_payload(
    rec: Recording,
    *,
    session_id: str | None = None,
    created_at: str | None = None,
    config: PipelineConfig | None = None,
    recorded_by: dict[str, int] | None = None,
) -> SessionPayload:
    """Filters the recording and returns the session (raw + filtered + the per-frame angle SDs + a small params
    summary), saying which device and patient recorded it (recorded_by). The settings default to the recording
    device's (config_for_device). The raw recording filtered and stored is the one the file gives back
    (session_file.as_stored: positions on the file's grid), so the server filtering the stored raw recording again
    with the same settings gets the same filtered recording."""
    config = config or config_for_device(rec.meta.device)
    rec = as_stored(rec)
    result = process(rec, config=config)
    params = pipeline_params(config, result)
    payload = SessionPayload(session_id=session_id or str(uuid.uuid4()), raw=rec, filtered=result.filtered,
                             params=params, recorded_by=recorded_by, angle_sd=result.angle_sd)  # fmt: skip
    if created_at is not None:
        payload.created_at = created_at
    return payload


def queue_session(
    queue: SessionQueue,
    rec: Recording,
    *,
    created_at: str | None = None,
    session_id: str | None = None,
    recorded_by: dict[str, int] | None = None,
    say: Callable[[str], None] = log.warning,
) -> Path:
    """Holds the raw session durably, filters it, queues the full session; returns the pending file.

    recorded_by: the pairing that recorded it (AgentConfig.recorded_by), written into the file. When the filter
    fails the raw session is queued instead (the server can filter it), so nothing is lost. When the disk is full
    the frames stay in memory: the family is told through say, and the session is written once there is room
    (kinect_agent.disk_full); this returns only then.
    """
    if created_at is None:  # the session started when its first frame was taken
        start = datetime.now(UTC) - timedelta(seconds=rec.duration)
        created_at = start.isoformat(timespec="seconds").replace("+00:00", "Z")
    raw = SessionPayload(session_id=session_id or str(uuid.uuid4()), raw=rec, created_at=created_at,
                         recorded_by=recorded_by)  # fmt: skip
    try:
        queue.hold(raw)
    except OSError as exc:
        if not is_disk_full(exc):
            raise
        say(f"{plain_words(exc)} The safety copy of this session could not be saved; its frames are kept in memory.")
    try:
        payload = make_payload(rec, session_id=raw.session_id, created_at=raw.created_at, recorded_by=recorded_by)
    except (ValueError, ProcessingError, FormatError) as exc:
        log.warning("filtering failed (%s: %s); queuing the raw session for the server to filter", type(exc).__name__,
                    exc)  # fmt: skip
        payload = raw
    path = write_when_space(lambda: queue.enqueue(payload), what="This session", say=say)
    queue.release(raw.session_id)
    return path
