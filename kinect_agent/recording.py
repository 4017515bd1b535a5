"""Recording: one skeleton sequence with times, positions, tracking states and metadata."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from kinect_agent import skeleton
from kinect_agent.skeleton import NOT_TRACKED, TRACKED

DEVICES = ("kinect1", "kinect2", "azure_kinect", "femto", "mocap", "simulator", "webcam", "unknown")


@dataclass
class Metadata:
    """What is known about how a recording was made. Unknown fields stay None."""

    device: str = "unknown"  # one of DEVICES
    rate_hz: float | None = None  # nominal frame rate of the source
    subject: str | None = None
    exercise: str | None = None
    view_deg: float | None = None  # camera angle from the frontal direction
    pose: str | None = None  # "sitting" or "standing"
    source: str | None = None  # file or device the data came from
    history: list[str] = field(default_factory=list)  # processing steps, oldest first
    extra: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """Returns the metadata as JSON-ready data."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Metadata:
        """Builds metadata from `to_dict` output, ignoring unknown keys; raises ValueError naming a field of the
        wrong type (a text where a number belongs, a list where a text belongs, ...)."""
        if not isinstance(data, dict):
            raise ValueError(f"metadata must be an object, got {type(data).__name__}")
        names = {f.name for f in dataclasses.fields(cls)}
        known = {k: v for k, v in data.items() if k in names}
        for key, value in known.items():
            _check_meta_field(key, value)
        known["history"] = list(known.get("history") or [])
        known["extra"] = dict(known.get("extra") or {})
        return cls(**known)


@dataclass
class Recording:
    """A skeleton sequence on the 20-joint model of `kinect_agent.skeleton`.

    t: (T,) float64, seconds, strictly increasing.
    positions: (T, J, 3) float64, metres, camera frame (y up); NaN = not tracked.
    state: (T, J) int8, 0 not tracked, 1 inferred, 2 tracked; 0 exactly where positions are NaN.
    meta: how the recording was made and processed.
    """

    t: np.ndarray
    positions: np.ndarray
    state: np.ndarray
    meta: Metadata = field(default_factory=Metadata)

    def __post_init__(self) -> None:
        self.t = np.asarray(self.t, dtype=np.float64)
        self.positions = np.asarray(self.positions, dtype=np.float64)
        self.state = np.asarray(self.state, dtype=np.int8)
        n = self.t.shape[0] if self.t.ndim == 1 else -1
        _check_shape("t", self.t.shape, (n,))
        _check_shape("positions", self.positions.shape, (n, skeleton.J, 3))
        _check_shape("state", self.state.shape, (n, skeleton.J))
        if not np.all(np.isfinite(self.t)):
            raise ValueError("t must be finite")
        bad = np.flatnonzero(np.diff(self.t) <= 0)
        if bad.size:
            i = int(bad[0]) + 1
            raise ValueError(f"t must be strictly increasing: frame {i} has t={self.t[i]} after t={self.t[i - 1]}")
        if np.any((self.state < NOT_TRACKED) | (self.state > TRACKED)):
            raise ValueError("state must be 0 (not tracked), 1 (inferred) or 2 (tracked)")
        missing = ~np.all(np.isfinite(self.positions), axis=-1)
        if np.any(missing & (self.state != NOT_TRACKED)):
            f, j = np.argwhere(missing & (self.state != NOT_TRACKED))[0]
            raise ValueError(f"frame {f}, joint {skeleton.JOINTS[j]}: position is NaN/inf but state is not 0")
        self.positions[missing] = np.nan

    @classmethod
    def from_positions(cls, t: np.ndarray, positions: np.ndarray, meta: Metadata | None = None) -> Recording:
        """Builds a recording whose state is 2 wherever a position is finite and 0 elsewhere.

        t: (T,) s. positions: (T, J, 3) m, NaN = not tracked.
        """
        positions = np.asarray(positions, dtype=np.float64)
        finite = np.all(np.isfinite(positions), axis=-1)
        state = np.where(finite, TRACKED, NOT_TRACKED).astype(np.int8)
        return cls(t, positions, state, meta or Metadata())

    @property
    def n_frames(self) -> int:
        """Number of frames T."""
        return int(self.t.shape[0])

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame (0 for fewer than two frames)."""
        return float(self.t[-1] - self.t[0]) if self.n_frames > 1 else 0.0

    @property
    def rate_hz(self) -> float:
        """The nominal rate if known, else the median rate of the time stamps."""
        if self.meta.rate_hz:
            return float(self.meta.rate_hz)
        if self.n_frames < 2:
            return 0.0
        return float(1.0 / np.median(np.diff(self.t)))

    def tracked(self) -> np.ndarray:
        """Returns (T, J) bool: True where a position is present (state 1 or 2)."""
        return self.state != NOT_TRACKED

    def segment_lengths(self) -> np.ndarray:
        """Returns (T, 14) segment lengths in metres (SEGMENT_NAMES order), NaN where untracked."""
        return skeleton.segment_lengths(self.positions)

    def replace(self, step: str | None = None, **changes: Any) -> Recording:
        """Returns a copy with fields changed and, if given, a processing step added to the history."""
        meta = changes.pop("meta", None) or dataclasses.replace(
            self.meta, history=list(self.meta.history), extra=dict(self.meta.extra)
        )
        if step:
            meta.history.append(step)
        fields = {"t": self.t.copy(), "positions": self.positions.copy(), "state": self.state.copy()}
        fields.update(changes)
        return Recording(meta=meta, **fields)

    def slice(self, start: int, stop: int) -> Recording:
        """Returns frames start..stop-1 as a new recording."""
        return self.replace(t=self.t[start:stop], positions=self.positions[start:stop], state=self.state[start:stop])

    @classmethod
    def concatenate(cls, parts: list[Recording], gap_s: float | None = None) -> Recording:
        """Joins recordings end to end; each part's clock restarts one frame (or gap_s) after the previous end."""
        if not parts:
            raise ValueError("concatenate needs at least one recording")
        times, offset = [], 0.0
        for part in parts:
            step = gap_s if gap_s is not None else (1.0 / part.rate_hz if part.rate_hz > 0 else 1.0)
            t = part.t - part.t[0] + offset
            times.append(t)
            offset = float(t[-1]) + step
        meta = dataclasses.replace(parts[0].meta, history=list(parts[0].meta.history), extra=dict(parts[0].meta.extra))
        meta.extra["concatenated_from"] = [p.meta.source for p in parts]
        meta.extra["part_start_s"] = [float(t[0]) for t in times]
        return cls(
            np.concatenate(times),
            np.concatenate([p.positions for p in parts]),
            np.concatenate([p.state for p in parts]),
            meta,
        )


_NUMBERS = {"rate_hz", "view_deg"}
RATE_RANGE_HZ = (1.0, 1000.0)  # no camera or motion capture records slower or faster
_LISTS_OF_TEXT = {"history"}
_OBJECTS = {"extra"}


def _check_meta_field(key: str, value: Any) -> None:
    """Raises ValueError when a metadata field has the wrong type (None is always allowed)."""
    if value is None:
        return
    if key in _NUMBERS:
        ok = isinstance(value, int | float) and not isinstance(value, bool) and np.isfinite(value)
        if ok and key == "rate_hz":  # as the session file's timing rule: frames 1 ms to 1 s apart
            ok = RATE_RANGE_HZ[0] <= value <= RATE_RANGE_HZ[1]
        low, high = RATE_RANGE_HZ
        expected = "a finite number" + (f" in [{low:g}, {high:g}] Hz" if key == "rate_hz" else "")
    elif key in _LISTS_OF_TEXT:
        ok, expected = isinstance(value, list) and all(isinstance(v, str) for v in value), "a list of texts"
    elif key in _OBJECTS:
        ok, expected = isinstance(value, dict), "an object"
    else:
        ok, expected = isinstance(value, str) and len(value) <= 1000, "a text of at most 1000 characters"
    if not ok:
        raise ValueError(f"{key} must be {expected}, got {str(value)[:80]!r}")


def _check_shape(name: str, actual: tuple[int, ...], expected: tuple[int, ...]) -> None:
    if len(actual) != len(expected) or any(e >= 0 and a != e for a, e in zip(actual, expected, strict=True)):
        shown = tuple("T" if e < 0 else e for e in expected)
        raise ValueError(f"{name} must have shape {shown}, got {actual}")
