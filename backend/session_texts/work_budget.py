"""How much work a session file can make the server do: the server's own pipeline settings, and frames thinned by time.

A session file is written by whoever uploads it, so nothing in it may choose the server's work:
- SERVER_PIPELINE: the outlier model and its threshold behind the session page's tracking-error strip and the
  replay's outlier marks run with the server's settings (this version's PipelineConfig defaults). What the file's
  params["config"] says about the agent's processing is stored and shown (processing.file_params), never obeyed:
  its outlier_iterations, outlier_window_s, ... would otherwise set the CPU and memory a request costs.
- analysis_frames: the server analyses at most MAX_ANALYSIS_RATE_HZ frames per second of recording. Frames closer
  in time than 1 / MAX_ANALYSIS_RATE_HZ (25 ms) to the last kept one are skipped, so the frames analysed are at
  most min(T, 40 × duration_s + 1) whatever the file's frame times, and any two kept frames are ≥ 25 ms apart
  (the outlier model's window, 0.5 s, then spans at most 21 frames). A 30 Hz camera's frames, jitter included
  (33 ± 8 ms), are all kept; a 1 kHz file is analysed at ≤ 40 Hz.

With both, a request's work is linear in the recording's duration and bounded by its frame count. The budget,
checked by bench/attack.py (family "file chooses the work") on SQLite and PostgreSQL, is BUDGETS[request]: CPU
seconds and bytes of memory per started BUDGET_PER_S (10 minutes) of recording. It is about twice what an ordinary
10-minute 30 Hz set costs (bench/README.md, "File chooses the work"), so any file that asks for more than its
duration is worth fails the check.
"""

from __future__ import annotations

import math

import numpy as np

from kinect_agent.formats.session_file import SessionPayload
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.recording import Recording

SERVER_PIPELINE = PipelineConfig()  # the server's own settings; a file's params["config"] is recorded, not obeyed
MAX_ANALYSIS_RATE_HZ = 40.0  # frames analysed per second of recording, at most
BUDGET_PER_S = 600.0  # the recording time a budget is given for, s
# request -> (CPU seconds, bytes of memory above the request's start) per started BUDGET_PER_S of recording
BUDGETS: dict[str, tuple[float, int]] = {
    "upload": (2.0, 256 * 2**20),
    "detail": (8.0, 512 * 2**20),
    "replay": (20.0, 512 * 2**20),
    "export": (8.0, 512 * 2**20),  # one download's build (csv, trc, bvh, fhir), by a worker past the request's limits
}
# (CPU seconds, bytes) one download may cost when built in the request, whatever its recording: the request builds
# it only within COACH_EXPORT_DIRECT_MAX_S and _FRAMES (backend.sessions.prepared_export), set so that it holds
EXPORT_IN_REQUEST: tuple[float, int] = (2.0, 256 * 2**20)


def budget(duration_s: float, request: str = "detail") -> tuple[float, int]:
    """Returns (CPU seconds, bytes) one request or build ("upload", "detail", "replay", "export") may spend on a
    recording of duration_s seconds."""
    units = max(1, math.ceil(max(duration_s, 0.0) / BUDGET_PER_S))
    cpu, memory = BUDGETS[request]
    return cpu * units, memory * units


def analysis_frames(t: np.ndarray, max_rate_hz: float = MAX_ANALYSIS_RATE_HZ) -> np.ndarray:
    """Returns the indices (K,) of the frames to analyse: each frame at least 1 / max_rate_hz after the last kept one.

    t: (T,) float, seconds, increasing. K ≤ min(T, max_rate_hz × (t[-1] − t[0]) + 1); index 0 is always kept.
    """
    t = np.asarray(t, dtype=np.float64)
    if len(t) < 2:
        return np.arange(len(t))
    spacing = 1.0 / max_rate_hz
    if float(np.min(np.diff(t))) >= spacing:
        return np.arange(len(t))
    keep = [0]
    i, n = 0, len(t)
    while True:
        i = int(np.searchsorted(t, t[i] + spacing, side="left"))
        if i >= n:
            break
        keep.append(i)
    return np.asarray(keep, dtype=np.intp)


def thinned(payload: SessionPayload) -> SessionPayload:
    """Returns the payload with raw, filtered and angle SDs at analysis_frames of the raw times (itself when every
    frame is kept). A filtered recording of another length than the raw one is left as it is (callers refuse it)."""
    raw = payload.raw
    keep = analysis_frames(raw.t)
    if len(keep) == raw.n_frames:
        return payload
    filtered = payload.filtered
    if filtered is not None and filtered.n_frames == raw.n_frames:
        filtered = _frames(filtered, keep)
    angle_sd = payload.angle_sd
    if angle_sd is not None:
        angle_sd = {k: v[keep] if len(v) == raw.n_frames else v for k, v in angle_sd.items()}
    return SessionPayload(
        session_id=payload.session_id,
        raw=_frames(raw, keep),
        filtered=filtered,
        params=payload.params,
        created_at=payload.created_at,
        recorded_by=payload.recorded_by,
        angle_sd=angle_sd,
    )


def _frames(rec: Recording, keep: np.ndarray) -> Recording:
    step = f"server: {len(keep)} of {rec.n_frames} frames analysed (≤ {MAX_ANALYSIS_RATE_HZ:g} per second)"
    return rec.replace(step=step, t=rec.t[keep], positions=rec.positions[keep], state=rec.state[keep])
