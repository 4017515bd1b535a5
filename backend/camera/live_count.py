"""The live count of camera sets: each new batch goes through the webcam's live filter (processing.online.live_filter:
the joints filter's causal pass, on the session file's position grid) and the live count (the same
kinect_agent.processing.online and kinect_agent.analysis.live a home agent runs), and the status goes to the
patient's pages as the same live.progress event a home agent's set sends. The stored session's count is counted on
the same causal pass (kinect_agent.analysis.live.counting_positions), so the saved count is the live count's.

The filter's state lives in this process, one per set (at most MAX_SETS, the least recently used dropped). A batch
that does not follow the state's last batch (a set continued through another worker, a state dropped, a batch
rolled back) rebuilds the state from the set's stored batches: the count is the same, only slower once.

The repetition counter's first evaluations (and, for the chain's filter, its numba kernels) cost most on a
process's first set: start_warm_up() does that in a background thread when
the server starts (Settings.LIVE_WARM_UP), so that the first batch of the first set is answered as fast as any.
"""

from __future__ import annotations

import collections
import logging
import threading
import time
import uuid
from dataclasses import dataclass
from typing import Any

import numpy as np
from sqlalchemy.orm import Session

from backend.camera import service
from backend.camera.models import CameraSet
from backend.camera.schemas import BatchOut
from backend.camera.skeleton import WEBCAM, camera_frames, pipeline_config
from backend.events.hub import Event, publish
from backend.exercises.models import Exercise
from kinect_agent.analysis.live import LiveCount, LiveStatus
from kinect_agent.formats.session_file import on_grid
from kinect_agent.processing.joint_smoother import JointFilter
from kinect_agent.processing.online import OnlineFilter, live_filter
from kinect_agent.sources.simulator import simulate
from kinect_agent.sources.webcam.landmarks import LandmarkBatch

MAX_SETS = 64
WARM_UP_S = 3.0  # s of a simulated squat run through the live count at start-up: the filter's start and 12 evaluations
log = logging.getLogger(__name__)


@dataclass
class _LiveSet:
    """The online filter and live count of one set, after batch `seq`."""

    seq: int
    online: OnlineFilter | JointFilter
    counter: LiveCount
    status: LiveStatus
    t_last: float | None = None


_STATES: collections.OrderedDict[uuid.UUID, _LiveSet] = collections.OrderedDict()
_LOCK = threading.Lock()


def _fresh(angles: tuple[str, ...]) -> _LiveSet:
    return _LiveSet(
        -1,
        live_filter(pipeline_config()),
        LiveCount(angles, device=WEBCAM),
        LiveStatus(0, None, None, None, 0.0),
    )


def _feed(state: _LiveSet, batch: LandmarkBatch) -> None:
    """Runs the batch's frames through the state's filter and count."""
    if batch.n_frames == 0:
        return
    positions, tracking = camera_frames(batch)
    positions = on_grid(positions)  # the numbers the stored session file holds: the stored count sees the same
    for k in range(batch.n_frames):
        t = float(batch.t[k])
        filtered = state.online.step(t, positions[k], tracking[k])
        state.status = state.counter.add(t, positions[k], tracking[k], filtered)
        state.t_last = t


def _state_for(
    db_session: Session, row: CameraSet, seq: int, batch: LandmarkBatch | None, angles: tuple[str, ...]
) -> _LiveSet:
    """Returns the set's live state after batch seq (batch: its frames when new, None when repeated)."""
    state = _STATES.get(row.id)
    if state is not None and batch is not None and state.seq == seq - 1:
        _feed(state, batch)
        state.seq = seq
    elif state is None or state.seq < seq:
        state = _fresh(angles)
        for stored in service.set_batches(db_session=db_session, set_id=row.id, upto_seq=seq):
            _feed(state, stored)
        state.seq = seq
    _STATES[row.id] = state
    _STATES.move_to_end(row.id)
    while len(_STATES) > MAX_SETS:
        _STATES.popitem(last=False)
    return state


def advance(
    *, db_session: Session, row: CameraSet, seq: int, batch: LandmarkBatch | None, fps: float | None
) -> BatchOut:
    """Returns the live status after batch seq of the set row and, for a new batch, publishes it as live.progress.

    batch: the new batch's frames (None: a repeated batch, nothing is fed twice)."""
    exercise = db_session.get(Exercise, row.exercise_id)
    assert exercise is not None
    angles = tuple(exercise.defining_angles)
    with _LOCK:
        try:
            state = _state_for(db_session, row, seq, batch, angles)
        except (ValueError, FloatingPointError, np.linalg.LinAlgError):
            # the live count is a courtesy: the batch is stored whatever happens here, the end analyses it all
            log.exception("live count of camera set %s failed at batch %s", row.id, seq)
            failed = _STATES.pop(row.id, None)
            state = failed if failed is not None else _fresh(angles)
        status, t_last = state.status, state.t_last
    out = BatchOut(
        set_id=str(row.id),
        seq=seq,
        repeated=batch is None,
        last_seq=row.last_seq,
        n_frames=row.n_frames,
        count=status.count,
        target=row.target_reps,
        angle_name=status.angle_name,
        angle_deg=None if status.angle_deg is None else round(status.angle_deg, 1),
        hint=status.hint,
        still_s=round(status.still_s, 2),
    )
    if batch is not None:
        data = {
            "set_id": str(row.id),
            "exercise_slug": exercise.slug,
            "state": "recording",
            "count": out.count,
            "target": out.target,
            "angle_name": out.angle_name,
            "angle_deg": out.angle_deg,
            "hint": out.hint,
            "elapsed_s": round(t_last or 0.0, 2),
            "session_id": str(row.id),
            "sent_at": time.time(),
            "device": WEBCAM,
            "fps": fps,
        }
        publish(db_session, Event("live.progress", row.patient_id, data))
    return out


def final_count(set_id: uuid.UUID) -> int | None:
    """Returns the live count this process holds for a set (None when it holds none), for the end message."""
    with _LOCK:
        state = _STATES.get(set_id)
        return None if state is None else state.counter.final()


def forget(set_id: uuid.UUID) -> None:
    """Drops the live state of a set that ended."""
    with _LOCK:
        _STATES.pop(set_id, None)


def warm_up() -> float:
    """Runs the camera sets' live count (live_filter with the webcam's settings, then LiveCount, frame by frame)
    over the first WARM_UP_S seconds of a simulated squat, so that its compiled code is ready; returns the seconds it
    took."""
    started = time.perf_counter()
    rec = simulate("squat", 1, seed=0)[0]
    state = _fresh(("knee_flexion_L", "knee_flexion_R"))
    for k in range(int(np.searchsorted(rec.t, rec.t[0] + WARM_UP_S))):
        t = float(rec.t[k])
        state.status = state.counter.add(t, rec.positions[k], rec.state[k], state.online.step(t, rec.positions[k],
                                                                                           rec.state[k]))  # fmt: skip
    state.counter.final()
    return time.perf_counter() - started


_WARMING: dict[str, Any] = {"thread": None}


def start_warm_up() -> threading.Thread:
    """Starts warm_up() in a background thread, once per process (later calls return the same thread)."""
    with _LOCK:
        thread = _WARMING["thread"]
        if thread is None:

            def run() -> None:
                try:
                    log.info("camera live count ready in %.1f s", warm_up())
                except Exception:  # noqa: BLE001 - a failed warm-up only means the first set compiles it
                    log.exception("warming up the camera live count failed")

            thread = threading.Thread(target=run, name="camera-warm-up", daemon=True)
            _WARMING["thread"] = thread
            thread.start()
        return thread
