"""Live feedback while a patient does a set: the repetition count, the defining angle now, and a hint in plain words
when the camera sees the patient badly. Frames arrive one by one (about 30 Hz) from the online filter.

Count. The same logic as the server's analysis of a stored session (kinect_agent/analysis/report.py): the filtered
positions are smoothed (series.smooth_positions), turned into counting angles (angles.counting_angles) and
counted (repetitions.count_repetitions, with the rest level where the set starts). It runs every `every_s`
seconds of recording on a window of recent frames, not at every frame. The window starts CONTEXT_S before the
cut `cut_t`; repetitions before the cut were counted already (`frozen`), so the count is frozen + the window's
repetitions whose middle is after the cut (their start may move by a few frames from one window to the next)
and that ended DONE_S before the newest frame (a repetition counts once the patient is back at rest). When the
window grows longer than window_s, the repetitions that ended more than SETTLE_S ago are frozen and the cut moves
to the end of the last of them (with none, to 2 × SETTLE_S before now): the cost of an evaluation stays bounded
(about window_s of frames) however long the set. The shown count never decreases within a set.
Confirmed. Each evaluation re-decides the whole window (the counter's rules are relative: min_ratio × the median
amplitude, the median spacing), so where the view is unsteady (left and right labels flickering) a pass over part of
the set can count fragments of one repetition that the pass over the whole set drops. An evaluation that counts fewer
than the one before, or more than one more (repetitions found in frames already seen), re-decides; for UNSETTLED_S
after one, a count is shown only once every evaluation of the last CONFIRM_S seconds (at least two) reached it.
Otherwise (the evaluations agree) a new repetition is shown at once. final() shows the whole set's count as it is
(a repetition the counter recognises late is never lost).
Floor. A device with a NoiseFloor (the webcam) drops excursions smaller than its floor, measured once on the set's
first START_S seconds (amplitude_floor, from the frames of those seconds only), as soon as they are over; until
then its bound. The stored count measures it on the same frames (kinect_agent/analysis/report.py): one floor.
Still. still_s counts the seconds since the dominant defining angle last moved: its range over the last
MOVE_WINDOW_S seconds reached MOVE_DEG. A gap of more than GAP_S between two frames (a browser's page hidden or
reloaded, its landmarker restarting, nobody followed) is not counted: nobody saw whether the patient moved then, so
a set does not end as still as soon as its pictures come back.
Hints. From the raw frames of the last HINT_S seconds, in this order: the trunk (ROOT, SPINE) seen in less than
half of them; the trunk closer than NEAR_M or farther than FAR_M; the trunk off-centre by more than
OFF_CENTRE_FRAC of half the horizontal field of view; the limbs of the defining angles not tracked in more than
LIMB_MISSING of them. The thresholds are those of the server's camera advice after a session
(backend/session_texts/camera_advice.py); the agent does not import the server, so they are repeated here.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from kinect_agent.analysis import series
from kinect_agent.analysis.angles import counting_angles
from kinect_agent.analysis.repetitions import (
    START_S,
    Repetition,
    RepetitionParams,
    RepetitionResult,
    count_repetitions,
)
from kinect_agent.body.angles import body_frame, joint_angles
from kinect_agent.processing.config import config_for_device
from kinect_agent.processing.joint_smoother import forward_joints
from kinect_agent.recording import Recording
from kinect_agent.skeleton import INDEX, NOT_TRACKED

CONTEXT_S = 20.0
SETTLE_S = 5.0
DONE_S = 0.2
CONFIRM_S = 1.0  # s: while unsettled, a count is shown once every evaluation of this many seconds reached it
UNSETTLED_S = 5.0  # s after an evaluation that re-decided (module doc, "Confirmed")
MOVE_WINDOW_S = 2.0
MOVE_DEG = 10.0
GAP_S = 5.0  # s between two frames: longer, the time between them is not counted as still (module doc, "Still")
HINT_S = 1.0
NEAR_M, FAR_M = 1.5, 3.8  # as camera_advice.NEAR_M, FAR_M
OFF_CENTRE_FRAC = 0.5  # as camera_advice.OFF_CENTRE_FRAC
HALF_FOV_DEG = 35.0  # half of Kinect 2's 70° horizontal field of view
LIMB_MISSING = 0.3
_TRUNK = [INDEX["ROOT"], INDEX["SPINE"]]
_ARMS = {"L": ["SHO_L", "ELB_L", "WRI_L"], "R": ["SHO_R", "ELB_R", "WRI_R"]}
_LEGS = {"L": ["HIP_L", "KNE_L", "ANK_L"], "R": ["HIP_R", "KNE_R", "ANK_R"]}

HINT_OUT_OF_VIEW = "You are out of view: please step in front of the camera."
HINT_TOO_CLOSE = "Step back a little."
HINT_TOO_FAR = "Come a little closer."
HINT_OFF_CENTRE = "Move to the middle of the picture."
HINT_ARMS = "The camera cannot see your arms well."
HINT_LEGS = "The camera cannot see your legs well."


@dataclass(frozen=True)
class LiveStatus:
    """What the patient's page shows now: count so far, the defining angle (degrees), a hint, seconds without
    movement."""

    count: int
    angle_name: str | None
    angle_deg: float | None
    hint: str | None
    still_s: float


def limb_joints(angle_names: tuple[str, ...]) -> tuple[list[int], str | None]:
    """Returns (joint indices, "arms"|"legs"|None) of the limbs that the angles measure."""
    names, kind = [], None
    for name in angle_names:
        side = name[-1] if name[-2:] in ("_L", "_R") else None
        if side is None:
            continue
        if name.startswith(("shoulder", "elbow")):
            names += _ARMS[side]
            kind = kind or "arms"
        elif name.startswith(("hip", "knee")):
            names += _LEGS[side]
            kind = kind or "legs"
    return sorted({INDEX[n] for n in names}), kind


def hint(positions: np.ndarray, state: np.ndarray, limbs: list[int], kind: str | None) -> str | None:
    """Returns the hint for the raw frames of the last second, or None when the camera sees the patient well.

    positions: (K, J, 3) float, metres, camera frame, NaN = untracked. state: (K, J) 0/1/2.
    """
    if positions.shape[0] == 0:
        return None
    seen = np.all(state[:, _TRUNK] != NOT_TRACKED, axis=1) & np.all(np.isfinite(positions[:, _TRUNK]), axis=(1, 2))
    if seen.mean() < 0.5:
        return HINT_OUT_OF_VIEW
    trunk = positions[seen][:, _TRUNK].reshape(-1, 3)
    x, z = float(np.median(trunk[:, 0])), float(np.median(trunk[:, 2]))
    if z < NEAR_M:
        return HINT_TOO_CLOSE
    if z > FAR_M:
        return HINT_TOO_FAR
    if np.degrees(np.arctan2(abs(x), z)) > OFF_CENTRE_FRAC * HALF_FOV_DEG:
        return HINT_OFF_CENTRE
    if limbs and np.mean(state[:, limbs] == NOT_TRACKED) > LIMB_MISSING:
        return HINT_ARMS if kind == "arms" else HINT_LEGS
    return None


@dataclass(frozen=True)
class NoiseFloor:
    """A device's amplitude floor, measured on each set: an excursion of a defining angle below factor × the angle's
    spread (p90 − p10, degrees) over the set's first START_S seconds (the rest the live count's rest level is taken
    from), bounded to [min_deg, max_deg], is no repetition; max_deg before that rest has been seen."""

    factor: float
    min_deg: float
    max_deg: float


# Devices whose counts have a floor (others: none, 0). The webcam: its landmarker's angles wobble on a person standing
# by up to 17 degrees when it sees the person poorly, by a few when it sees them well (bench/README.md, "Webcam counts:
# a floor measured on the set").
DEVICE_NOISE_FLOOR: dict[str, NoiseFloor] = {"webcam": NoiseFloor(factor=3.0, min_deg=8.0, max_deg=20.0)}


def counting_params(device: str | None, floor_deg: float | None = None) -> RepetitionParams:
    """Returns the repetition rules of a live count of `device` (kinect_agent.recording.DEVICES; None: Kinect's).

    floor_deg: the set's amplitude floor (amplitude_floor); None: its device's before it is measured (max_deg)."""
    floor = DEVICE_NOISE_FLOOR.get(device or "")
    if floor is None:
        return RepetitionParams(rest="start")
    return RepetitionParams(rest="start", min_amplitude_deg=floor.max_deg if floor_deg is None else floor_deg)


def amplitude_floor(device: str | None, t: np.ndarray, positions: np.ndarray, names: tuple[str, ...]) -> float | None:
    """Returns a set's amplitude floor in degrees (NoiseFloor), 0 for a device without one, None while the set's first
    START_S seconds are not over (no frame after them yet).

    t: (T,) s; positions: (T, J, 3) m, camera frame, the positions the set is counted on (the live filter's causal
    pass). Only the frames of the first START_S seconds are read, conditioned on their own (series.smooth_positions,
    counting_angles), so that the live count, which measures it as soon as they are over, and the stored count,
    which has the whole set, measure the same numbers.
    """
    floor = DEVICE_NOISE_FLOOR.get(device or "")
    if floor is None:
        return 0.0
    n = int(np.searchsorted(t, t[0] + START_S, side="right")) if t.shape[0] else 0
    if n >= t.shape[0]:
        return None
    if n < 2:  # under 2 frames a second: no spread to measure
        return floor.max_deg
    smoothed = series.smooth_positions(t[:n], positions[:n])
    angles = counting_angles(smoothed, names, joint_angles(smoothed), body_frame(smoothed)[0])
    spreads = [float(np.subtract(*np.percentile(y[np.isfinite(y)], [90.0, 10.0]))) for y in angles.values()
               if np.isfinite(y).any()]  # fmt: skip
    if not spreads:
        return floor.max_deg
    return float(np.clip(floor.factor * max(spreads), floor.min_deg, floor.max_deg))


def done_repetitions(result: RepetitionResult, t: np.ndarray) -> list[Repetition]:
    """Returns the repetitions of result (counted over frame times t: (T,) s) that ended DONE_S before the newest
    frame: the patient is back at rest (one still under way may yet merge or shrink, and is not counted yet)."""
    return [r for r in result.repetitions if t[0] + r.end_s < t[-1] - DONE_S]


def counting_positions(recording: Recording) -> np.ndarray | None:
    """Returns (T, J, 3) m, camera frame, the positions a stored recording's repetitions are counted on when its
    device's live count runs the joints filter (the webcam: processing.online.live_filter), None otherwise.

    That filter's causal pass over the raw recording: the positions the live count saw frame by frame, so that the
    stored count and the live count are one count (the same positions, the same rules, rest="start"); the stored
    angles and ranges still come from the smoothed recording. Other devices are counted on the measured positions.
    """
    config = config_for_device(recording.meta.device)
    return forward_joints(recording, config) if config.offline_filter == "joints" else None


class LiveCount:
    """Counts one set's repetitions incrementally; add() takes each frame and returns what to show."""

    def __init__(
        self,
        angle_names: tuple[str, ...],
        *,
        every_s: float = 0.25,
        window_s: float = 60.0,
        params: RepetitionParams | None = None,
        device: str | None = None,
    ) -> None:
        if not angle_names:
            raise ValueError("LiveCount needs at least one defining angle")
        self.names = tuple(angle_names)
        self.every_s, self.window_s = every_s, window_s
        self.device = device
        # a set starts at rest; its end may be mid-movement. A device's floor: its bound until measured (_measure_floor)
        self.params = params or counting_params(device)
        self.floor_deg: float | None = None if device in DEVICE_NOISE_FLOOR else 0.0
        self.limbs, self.limb_kind = limb_joints(self.names)
        self._t: list[float] = []
        self._filtered: list[np.ndarray] = []
        self._raw: list[np.ndarray] = []
        self._state: list[np.ndarray] = []
        self.frozen = 0
        self.cut_t = math.nan  # s; the first frame's time until a window is frozen (NaN: no frame yet)
        self.shown = 0
        self._recent: list[tuple[float, int]] = []  # (s, count) of the evaluations of the last CONFIRM_S seconds
        self._redecided_t = -math.inf  # s, the last evaluation that re-decided (module doc, "Confirmed")
        self._next_eval = math.nan  # s
        self._last_moving = math.nan  # s
        self._status = LiveStatus(0, None, None, None, 0.0)

    def add(self, t: float, raw_positions: np.ndarray, raw_state: np.ndarray, filtered: np.ndarray) -> LiveStatus:
        """Takes one frame and returns the status to show.

        t: s, increasing. raw_positions: (J, 3) m camera frame, NaN = untracked; raw_state: (J,) 0/1/2;
        filtered: (J, 3) m, the online filter's output for the frame.
        """
        if self._t and t - self._t[-1] > GAP_S:
            self._last_moving += t - self._t[-1]
        self._t.append(float(t))
        self._filtered.append(np.asarray(filtered, dtype=np.float64))
        self._raw.append(np.asarray(raw_positions, dtype=np.float64))
        self._state.append(np.asarray(raw_state))
        if math.isnan(self.cut_t):
            self.cut_t, self._last_moving, self._next_eval = t, t, t + self.every_s
        if self.floor_deg is None and t > self._t[0] + START_S:  # amplitude_floor's frames are all in
            self._measure_floor()
        if t >= self._next_eval:
            self._next_eval = t + self.every_s
            self._evaluate()
        return self._status

    def final(self) -> int:
        """Returns the count of the whole set so far (evaluated on the newest frames, shown without confirmation)."""
        if len(self._t) >= 2:
            self._evaluate(final=True)
        return self._status.count

    def _measure_floor(self) -> None:
        """Sets the device's amplitude floor once the set's first START_S seconds are over (amplitude_floor): the
        frames are all still held then (nothing is frozen before window_s)."""
        floor = amplitude_floor(self.device, np.asarray(self._t), np.stack(self._filtered), self.names)
        if floor is not None:
            self.floor_deg = floor
            self.params = dataclasses.replace(self.params, min_amplitude_deg=floor)

    def _window(self) -> int:
        """Returns the index of the first frame of the evaluation window."""
        start = self.cut_t - CONTEXT_S
        return int(np.searchsorted(np.asarray(self._t), start))

    def _evaluate(self, final: bool = False) -> None:
        first = self._window()
        t = np.asarray(self._t[first:])
        now = float(t[-1])
        angle_name, angle_deg, count = None, None, self.shown
        if t.shape[0] >= 2:
            smoothed = series.smooth_positions(t, np.stack(self._filtered[first:]))
            clinical = joint_angles(smoothed)
            angles = counting_angles(smoothed, self.names, clinical, body_frame(smoothed)[0])
            result = count_repetitions(t, angles, self.names, self.params)
            ends = np.array([t[0] + r.end_s for r in result.repetitions])
            middles = np.array([t[0] + 0.5 * (r.start_s + r.end_s) for r in result.repetitions])
            after_cut = middles > self.cut_t
            done = np.isin(np.arange(len(result.repetitions)), [r.index for r in done_repetitions(result, t)])
            count = self.frozen + int((after_cut & done).sum())
            angle_name = result.defining_angle or self.names[0]
            y = angles[angle_name]
            angle_deg = float(y[-1]) if np.isfinite(y[-1]) else None
            recent = y[t >= now - MOVE_WINDOW_S]
            recent = recent[np.isfinite(recent)]
            if recent.size and np.ptp(recent) >= MOVE_DEG:
                self._last_moving = now
            if now - self.cut_t > self.window_s:
                self._freeze(ends[after_cut], now)
            if not final:
                count = self._confirmed(now, count)
        self.shown = max(self.shown, count)
        k = min(max(0, len(self._t) - int(round(HINT_S * self._rate()))), len(self._t) - 1)  # < 1 fps: the newest
        raw, state = np.stack(self._raw[k:]), np.stack(self._state[k:])
        self._status = LiveStatus(self.shown, angle_name, angle_deg, hint(raw, state, self.limbs, self.limb_kind),
                                  now - self._last_moving)  # fmt: skip

    def _confirmed(self, now: float, count: int) -> int:
        """Returns the count an evaluation at `now` (s) that counted `count` may show (module doc, "Confirmed"): the
        count itself while the evaluations agree, else the least count of the last CONFIRM_S seconds' evaluations."""
        previous = self._recent[-1][1] if self._recent else None
        if previous is not None and not previous <= count <= previous + 1:
            self._redecided_t = now
        self._recent = [(t, c) for t, c in self._recent if t >= now - CONFIRM_S] + [(now, count)]
        if now - self._redecided_t > UNSETTLED_S:
            return count
        return min(c for _, c in self._recent) if len(self._recent) >= 2 else self.shown

    def _freeze(self, ends: np.ndarray, now: float) -> None:
        """Freezes the window's repetitions that ended more than SETTLE_S ago and moves the cut past them."""
        done = ends[ends <= now - SETTLE_S]
        self.frozen += int(done.size)
        # no repetition for a whole window (the patient rests): the cut follows, so the window stays bounded
        self.cut_t = float(done.max()) if done.size else now - 2 * SETTLE_S
        keep = self._window()
        del self._t[:keep], self._filtered[:keep], self._raw[:keep], self._state[:keep]

    def _rate(self) -> float:
        n = len(self._t)
        if n < 2:
            return 30.0
        return (n - 1) / max(self._t[-1] - self._t[0], 1e-6)
