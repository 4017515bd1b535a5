"""`kinect-agent run --source SOURCE [FILE] --exercise NAME [--reps N]`: capture, filter, queue, upload.

capture (simulator | replay FILE | kinect2 | azure | webcam [--camera N] [VIDEO])
  -> the raw session is held durably in queue/captured/ (a crash in the filter loses nothing)
  -> pipeline (outlier removal + kinematic UKF) -> session file with raw + filtered recordings
  -> queue/pending/ (atomic, fsynced) -> upload (the file stays queued when the server is down)
"""

from __future__ import annotations

import argparse
import re
import sys
import uuid
from datetime import UTC, datetime, timedelta
from pathlib import Path

from kinect_agent import formats
from kinect_agent.config import load_config
from kinect_agent.formats.session_file import SessionPayload
from kinect_agent.processing.config import PipelineConfig, config_for_device
from kinect_agent.processing.pipeline import VERSION, process
from kinect_agent.queue import SessionQueue
from kinect_agent.recording import Recording
from kinect_agent.upload import DrainReport, Uploader, drain

NAME = "run"
HELP = "Record one exercise session, filter it, queue it on disk and upload it (queued first, even when offline)."
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


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares the run options."""
    parser.add_argument("--source", required=True, choices=sorted(SOURCE_NAMES), help="where frames come from")
    parser.add_argument("file", nargs="?", type=Path,
                        help="recording to replay (--source replay) or video to analyse (--source webcam)")  # fmt: skip
    parser.add_argument("--camera", type=int, help="camera index (--source webcam; default 0)")
    parser.add_argument("--model", choices=("lite", "full"), help="pose model (--source webcam; default lite)")
    parser.add_argument("--exercise", required=True, help="exercise slug, e.g. shoulder_abduction")
    parser.add_argument("--reps", type=int, default=10, help="repetitions to simulate (simulator; default 10)")
    parser.add_argument("--seconds", type=float, default=60.0, help="recording length for cameras (default 60 s)")
    parser.add_argument("--seed", type=int, default=0, help="simulator seed (default 0)")
    parser.add_argument("--no-upload", action="store_true", help="only queue the session; upload later")


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
    device's (config_for_device)."""
    config = config or config_for_device(rec.meta.device)
    result = process(rec, config=config)
    q = result.quality
    params = {
        "pipeline": VERSION,
        "config": config.model_dump(),
        # no timings here: the same recording must give the same bytes (the server deduplicates on the hash)
        "quality": {k: q[k] for k in ("n_frames", "n_outliers", "n_gated", "frames_without_observation")},
        "segment_lengths_m": q["segment_lengths_m"],
    }
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
) -> Path:
    """Holds the raw session durably, filters it, queues the full session; returns the pending file.

    recorded_by: the pairing that recorded it (AgentConfig.recorded_by), written into the file. When the filter
    fails the raw session is queued instead (the server can filter it), so nothing is lost.
    """
    if created_at is None:  # the session started when its first frame was taken
        start = datetime.now(UTC) - timedelta(seconds=rec.duration)
        created_at = start.isoformat(timespec="seconds").replace("+00:00", "Z")
    raw = SessionPayload(session_id=session_id or str(uuid.uuid4()), raw=rec, created_at=created_at,
                         recorded_by=recorded_by)  # fmt: skip
    queue.hold(raw)
    try:
        payload = make_payload(rec, session_id=raw.session_id, created_at=raw.created_at, recorded_by=recorded_by)
    except ValueError as exc:
        print(f"filtering failed ({exc}); queuing the raw session for the server to filter", file=sys.stderr)
        payload = raw
    path = queue.enqueue(payload)
    queue.release(raw.session_id)
    return path


def upload_now(queue: SessionQueue, server_url: str, token: str, *, transport=None) -> DrainReport:
    """One pass over the queue with the agent's credentials, logging each file on stderr."""
    with Uploader(server_url, token, transport=transport) as uploader:
        return drain(queue, uploader, log=lambda line: print(line, file=sys.stderr, flush=True))


def run(args: argparse.Namespace) -> int:
    """Captures, queues and (unless --no-upload) uploads one session; 0 once the session is safely queued."""
    config = load_config()
    queue = SessionQueue(config.queue_dir)
    queue.recover_held()
    rec = capture(args.source, exercise=args.exercise, file=args.file, reps=args.reps, seconds=args.seconds,
                  seed=args.seed, camera=args.camera, model=args.model)  # fmt: skip
    path = queue_session(queue, rec, recorded_by=config.recorded_by)
    print(f"{args.source}: {rec.n_frames} frames, {rec.duration:.1f} s of {args.exercise} -> {path}", file=sys.stderr)
    if not args.no_upload:
        report = upload_now(queue, config.server_url, config.device_token)
        if report.remaining:
            print(f"{report.remaining} session(s) wait in {queue.pending_dir}; run `kinect-agent upload` later",
                  file=sys.stderr)  # fmt: skip
    return 0
