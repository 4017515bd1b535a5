"""`kinect-agent upload [--once]`: send the queued sessions to the server (oldest first), then keep watching."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from pathlib import Path

import httpx

from kinect_agent.config import load_config
from kinect_agent.queue import SessionQueue
from kinect_agent.upload import DrainReport, Uploader, drain

NAME = "upload"
HELP = "Upload the queued sessions; with --once drain the queue and exit, else retry every --interval seconds."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares the upload options."""
    parser.add_argument("--once", action="store_true", help="one pass over the queue, then exit")
    parser.add_argument("--interval", type=float, default=30.0, help="seconds between passes (default 30)")
    parser.add_argument("--retry-rejected", action="store_true", help="move rejected sessions back to the queue first")
    parser.add_argument("--retry-held", action="store_true", help="move held sessions (the same server error again "
                        "and again) back to the queue first")  # fmt: skip


def upload_queue(
    home: str | Path | None = None,
    *,
    transport: httpx.BaseTransport | None = None,
    log: Callable[[str], None] | None = None,
) -> DrainReport:
    """One pass: loads the configuration, cleans crash leftovers, uploads the pending files."""
    config = load_config(home)
    queue = SessionQueue(config.queue_dir)
    queue.clean_partial()
    queue.recover_held()
    with Uploader(config.server_url, config.device_token, transport=transport) as uploader:
        return drain(queue, uploader, log=log)


def _say(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    """Drains the queue once (exit 0 when nothing is left pending, 1 otherwise) or forever."""
    if not args.interval > 0:
        raise ValueError(f"--interval must be a positive number of seconds, got {args.interval}")
    if args.retry_rejected or args.retry_held:
        queue = SessionQueue(load_config().queue_dir)
        if args.retry_rejected:
            _say(f"{len(queue.requeue_rejected())} rejected session(s) moved back to the queue")
        if args.retry_held:
            _say(f"{len(queue.requeue_held())} held session(s) moved back to the queue")
    while True:
        report = upload_queue(log=_say)
        _say(f"{report.count('sent')} sent, {report.count('rejected')} rejected, {report.count('held')} held, "
             f"{report.remaining} still queued")  # fmt: skip
        if args.once:
            return 0 if report.remaining == 0 and report.count("rejected") == report.count("held") == 0 else 1
        time.sleep(args.interval)
