"""`kinect-agent serve --source SOURCE [FILE]`: the home agent as a background service for the live loop.

It opens one connection to the server (kinect_agent/live/channel.py; no port is opened at home) and waits for the
patient to press Start on their page. Each Start records one set (live/set_recorder.py) with live feedback, then
queues the session on disk and uploads it. At start-up it connects at once (the patient's page shows the home
computer ready), uploads whatever waits in the queue, and meanwhile, in a thread of its own, filters and queues the
sets a crash interrupted (journal.py: those with at least 5 s of frames; a long set takes seconds to filter) and then
uploads them; it also retries the queue every --upload-every seconds. Ctrl-C or SIGTERM ends a running set (kept),
lets the recovery finish, and stops.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from pathlib import Path
from typing import Any

from kinect_agent.capture import SOURCE_NAMES, check_exercise, check_source_file, queue_session
from kinect_agent.commands.run import upload_now
from kinect_agent.config import AgentConfig, load_config
from kinect_agent.errors import DeviceUnavailable
from kinect_agent.live import journal
from kinect_agent.live.channel import CommandStream, Publisher
from kinect_agent.live.set_recorder import SetCommand, SetLimits, SetRecorder, failed_message
from kinect_agent.queue import SessionQueue
from kinect_agent.sources import Source, make_source

NAME = "serve"
HELP = "Run as the home computer's background service: record a set whenever the patient presses Start."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares the serve options."""
    parser.add_argument("--source", required=True, choices=sorted(SOURCE_NAMES), help="where frames come from")
    parser.add_argument("file", nargs="?", type=Path,
                        help="recording (--source replay) or video (--source webcam) for every set")  # fmt: skip
    parser.add_argument("--camera", type=int, help="camera index (--source webcam; default 0)")
    parser.add_argument("--model", choices=("lite", "full"), help="pose model (--source webcam; default lite)")
    parser.add_argument("--home", type=Path, help="agent folder (default $KINECT_AGENT_HOME)")
    parser.add_argument("--seed", type=int, default=0, help="simulator seed of the first set (default 0)")
    parser.add_argument("--still-end", type=float, default=20.0, metavar="S",
                        help="end a set after S seconds without movement (default 20)")  # fmt: skip
    parser.add_argument("--max-set", type=float, default=900.0, metavar="S", help="longest set, seconds (900)")
    parser.add_argument("--upload-every", type=float, default=300.0, metavar="S",
                        help="retry the upload queue every S seconds (default 300)")  # fmt: skip


def log(line: str) -> None:
    """Writes one line of the service's log (stderr)."""
    print(line, file=sys.stderr, flush=True)


class Uploads:
    """Drains the queue in a thread of its own, when asked (after a set) and every `every_s` seconds."""

    def __init__(self, queue: SessionQueue, config: AgentConfig, every_s: float) -> None:
        self.queue, self.config, self.every_s = queue, config, every_s
        self._wake, self._stop = threading.Event(), threading.Event()
        self._thread = threading.Thread(target=self._run, name="uploads", daemon=True)
        self._thread.start()

    def now(self) -> None:
        """Asks for a pass over the queue."""
        self._wake.set()

    def close(self) -> None:
        """Makes a last pass and stops."""
        self._stop.set()
        self._wake.set()
        self._thread.join(timeout=120)

    def _run(self) -> None:
        while True:
            if self.queue.pending():
                try:
                    upload_now(self.queue, self.config.server_url, self.config.device_token)
                except Exception as exc:  # noqa: BLE001 - the service keeps running; the files stay queued
                    log(f"upload pass failed ({exc}); the sessions stay queued")
            if self._stop.is_set():
                return
            self._wake.wait(self.every_s)
            self._wake.clear()


def recover_interrupted(queue: SessionQueue, folder: Path, recorded_by: dict[str, int] | None = None,
                        interrupted: list[journal.Interrupted] | None = None) -> int:  # fmt: skip
    """Queues the sets a crash interrupted (those long enough, as recorded by the pairing recorded_by) and removes
    their journals; returns how many. interrupted: those journal.recover listed (default: listed now). A set the
    queue already holds (pending, sent, ...) keeps that file."""
    kept = 0
    for found in journal.recover(folder) if interrupted is None else interrupted:
        place = queue.where(found.session_id) if found.recording is not None else None
        if place is not None:  # a stop between queuing the ended set and removing its journal: the queue has it whole
            log(f"the interrupted set {found.session_id} is already {place}: its journal is dropped")
        elif found.recording is not None:
            queue_session(queue, found.recording, created_at=found.created_at, session_id=found.session_id,
                          recorded_by=recorded_by, say=log)  # fmt: skip
            kept += 1
            log(f"kept the interrupted set {found.session_id} ({found.recording.duration:.0f} s)")
        else:
            log(f"dropped the interrupted set {found.session_id}: {found.reason}")
        journal.remove(folder, found.session_id)
    return kept


class Service:
    """The serve loop: commands in, one set at a time."""

    def __init__(self, args: argparse.Namespace, config: AgentConfig) -> None:
        self.args, self.config = args, config
        self.queue = SessionQueue(config.queue_dir)
        self.journal_dir = Path(config.queue_dir) / "recording"
        self.limits = SetLimits(still_end_s=args.still_end, max_s=args.max_set)
        self.n_sets = 0
        self.current: SetRecorder | None = None
        self.thread: threading.Thread | None = None

    def source_for(self, command: SetCommand) -> Source:
        """Returns the frame source of one set (the simulator plays the commanded exercise)."""
        kind = SOURCE_NAMES[self.args.source]
        if kind == "simulator":
            from kinect_agent.sources.simulator import SimulatorSource

            return SimulatorSource(command.exercise, reps_per_block=command.target_reps,
                                   seed=self.args.seed + self.n_sets)  # fmt: skip
        if kind == "webcam":
            return make_source(kind, file=self.args.file, camera=self.args.camera, model=self.args.model)
        return make_source(kind, file=self.args.file)

    def start(self, data: dict[str, Any], publisher: Publisher, uploads: Uploads) -> None:
        """Starts the commanded set unless one is running (then the command is refused with a message)."""
        command = SetCommand.from_message(data)
        check_exercise(command.exercise)
        if self.thread is not None and self.thread.is_alive():
            publisher.offer(failed_message(command, "A set is already being recorded."), keep=True)
            return
        try:
            source = self.source_for(command)
        except ValueError as exc:
            log(f"cannot start {command.exercise}: {exc}")
            publisher.offer(failed_message(command, "The home computer cannot record this exercise."), keep=True)
            return
        self.n_sets += 1
        self.current = SetRecorder(command, source, self.journal_dir, lambda m, k: publisher.offer(m, keep=k),
                                   self.limits)  # fmt: skip
        self.thread = threading.Thread(target=self._record, args=(self.current, uploads), name="set", daemon=True)
        self.thread.start()
        log(f"set {command.set_id}: recording {command.exercise}, target {command.target_reps}")

    def _record(self, recorder: SetRecorder, uploads: Uploads) -> None:
        try:
            result = recorder.run()
        except DeviceUnavailable as exc:
            log(f"set {recorder.command.set_id} failed: {exc}")
            recorder.publish(failed_message(recorder.command, "The camera stopped working. Check that it is "
                                                              "plugged in, then press Start again."), True)  # fmt: skip
            return
        except Exception as exc:  # noqa: BLE001 - a failed set must not stop the service; its journal stays
            log(f"set {recorder.command.set_id} failed: {exc}")
            recorder.publish(failed_message(recorder.command, "Recording stopped because of an error."), True)
            return
        log(f"set {recorder.command.set_id} ended ({result.reason}): {result.count} repetitions")
        if result.recording is not None and result.recording.n_frames >= 2:
            queue_session(self.queue, result.recording, created_at=result.created_at, session_id=result.session_id,
                          recorded_by=self.config.recorded_by, say=log)  # fmt: skip
            uploads.now()
        if result.journal is not None:
            result.journal.discard()

    def stop_set(self, data: dict[str, Any]) -> None:
        """Ends the running set if the command names it."""
        if self.current is not None and self.current.command.set_id == data.get("set_id"):
            self.current.stop()

    def finish(self) -> None:
        """Ends a running set and waits until it is queued."""
        if self.current is not None:
            self.current.stop()
        if self.thread is not None:
            self.thread.join(timeout=120)


class Recovery:
    """Filters and queues the interrupted sets in a thread of its own, then asks for an upload pass: the agent is
    connected (and shown ready) while a long set is filtered. The sets are listed before it starts, so a set
    recorded meanwhile (its own journal in the same folder) is never taken for an interrupted one."""

    def __init__(self, service: Service, uploads: Uploads) -> None:
        self.found = journal.recover(service.journal_dir)
        self._args = (service.queue, service.journal_dir, service.config.recorded_by, self.found)
        self._uploads = uploads
        self._thread = threading.Thread(target=self._run, name="recovery", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        if not self.found:
            return
        try:
            if recover_interrupted(*self._args):
                self._uploads.now()
        except Exception as exc:  # noqa: BLE001 - the journals stay: the next start recovers them
            log(f"recovering the interrupted sets failed ({type(exc).__name__}: {exc}); tried again at the next start")

    def join(self, timeout_s: float = 120.0) -> None:
        """Waits for the recovery to end (at a stop: its sets queued before the last upload pass)."""
        self._thread.join(timeout_s)


def _warm_up() -> None:
    """Readies the live loop's compiled code (kinect_agent.live.warmup) and logs how long it took."""
    from kinect_agent.live.warmup import cache_folders, kernel_counts, warm_up, where_cached

    try:
        seconds = warm_up()
        counts = kernel_counts()
        compiled = f"{counts['cache_misses']} kernels compiled (`kinect-agent prepare` does it once after an install), "
        log(f"live filter ready in {seconds:.1f} s; {compiled if counts['cache_misses'] else ''}"
            f"{counts['cache_hits']} loaded from numba's cache in {where_cached(cache_folders())}")  # fmt: skip
    except Exception as exc:  # noqa: BLE001 - the first set then compiles what it needs itself
        log(f"live filter warm-up failed: {type(exc).__name__}: {exc}")


def run(args: argparse.Namespace) -> int:
    """Serves until interrupted; 0 on a clean stop."""
    check_source_file(SOURCE_NAMES[args.source], args.file)
    if SOURCE_NAMES[args.source] == "webcam":  # a missing camera, package or model is said now, not at the first set
        probe = make_source("webcam", file=args.file, camera=args.camera, model=args.model)
        probe.open()
        probe.close()
    config = load_config(args.home)
    service = Service(args, config)
    service.queue.recover_held(older_than_s=0.0)  # this is the only agent of this queue: nothing is in progress
    uploads = Uploads(service.queue, config, args.upload_every)
    recovery = Recovery(service, uploads)  # in the background: the command stream below connects now
    publisher = Publisher(config.server_url, config.device_token, log=log)
    stream = CommandStream(config.server_url, config.device_token, log=log)
    stop = threading.Event()
    signal.signal(signal.SIGTERM, signal.default_int_handler)  # SIGTERM stops like Ctrl-C
    log(f"serving patient {config.patient_id} for {config.server_url} with source {args.source}")
    threading.Thread(target=_warm_up, name="warm-up", daemon=True).start()  # before the first Start, not after it
    try:
        for data in stream.commands(stop):
            try:
                service.start(data, publisher, uploads) if data["action"] == "start" else service.stop_set(data)
            except ValueError as exc:
                log(f"ignored a command: {exc}")
    except KeyboardInterrupt:
        log("stopping")
    finally:
        stop.set()
        stream.close()
        service.finish()
        recovery.join()
        publisher.close()
        uploads.close()
    return 0
