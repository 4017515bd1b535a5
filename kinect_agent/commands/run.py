"""`kinect-agent run --source SOURCE [FILE] --exercise NAME [--reps N]`: capture, filter, queue, upload
(kinect_agent.capture does the first four).

capture (simulator | replay FILE | kinect2 | azure | webcam [--camera N] [VIDEO])
  -> the raw session is held durably in queue/captured/ (a crash in the filter loses nothing)
  -> pipeline (outlier removal + kinematic UKF) -> session file with raw + filtered recordings
  -> queue/pending/ (atomic, fsynced) -> upload (the file stays queued when the server is down)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import httpx

from kinect_agent.capture import SOURCE_NAMES, capture, queue_session
from kinect_agent.config import load_config
from kinect_agent.disk_full import is_disk_full, plain_words
from kinect_agent.queue import SessionQueue
from kinect_agent.upload import DrainReport, Uploader, drain

NAME = "run"
HELP = "Record one exercise session, filter it, queue it on disk and upload it (queued first, even when offline)."


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


def upload_now(
    queue: SessionQueue, server_url: str, token: str, *, transport: httpx.BaseTransport | None = None
) -> DrainReport:
    """One pass over the queue with the agent's credentials, logging each file on stderr."""
    with Uploader(server_url, token, transport=transport) as uploader:
        return drain(queue, uploader, log=lambda line: print(line, file=sys.stderr, flush=True))


def _say(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    """Captures, queues and (unless --no-upload) uploads one session; 0 once the session is safely queued."""
    config = load_config()
    queue = SessionQueue(config.queue_dir)
    queue.recover_held()
    rec = capture(args.source, exercise=args.exercise, file=args.file, reps=args.reps, seconds=args.seconds,
                  seed=args.seed, camera=args.camera, model=args.model)  # fmt: skip
    path = queue_session(queue, rec, recorded_by=config.recorded_by, say=_say)
    print(f"{args.source}: {rec.n_frames} frames, {rec.duration:.1f} s of {args.exercise} -> {path}", file=sys.stderr)
    if not args.no_upload:
        try:
            report = upload_now(queue, config.server_url, config.device_token)
        except OSError as exc:
            if not is_disk_full(exc):
                raise
            _say(f"{plain_words(exc)} The session is saved and goes with `kinect-agent upload` once there is room.")
            return 0
        if report.remaining:
            print(f"{report.remaining} session(s) wait in {queue.pending_dir}; run `kinect-agent upload` later",
                  file=sys.stderr)  # fmt: skip
    return 0
