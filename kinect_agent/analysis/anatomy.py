"""What a joint can bend: the flexion past which a curve is the camera losing the limb, not the body (issue 24.1).

A flexion past its joint's FLEXION_LIMIT_DEG is withheld with the reason beyond_anatomy
(kinect_agent.analysis.reasons), which names that limit: an angle's range of motion (intervals.beyond_anatomy) and,
here, the numbers of a repetition measured on such a curve (its peak and amplitude, repetition_beyond_anatomy) and the
session's range of motion, the median of those amplitudes (rom_beyond_anatomy). Limits, in the angles' own
definitions (kinect_agent.body.angles), on mocap truth (bench/README.md):
    knee, elbow flexion of the joint centres  170°: the UI-PRMD Kinect reads seated knees at 173-178° where its Vicon
        reads 93-96°; HDM05's full squats (mocap, heels down) reach 163-166° (issue 24 audit).
    hip flexion (the thigh in the trunk's sagittal plane, 180 = along the trunk towards the neck)  190°: no frame of
        mocap passes 181.1° (UI-PRMD Vicon s01 deep squat, incorrect; HDM05 bd/bk 120.3°, CMU 13_29 166.8°, KERAAL
        Vicon 95.0°); the Kinect's thighs mistracked in sit-to-stands, hurdle steps and leg raises read 200-260°
        (bench/flexion_limit.py, "Hip flexion's anatomical limit").
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from kinect_agent.analysis import reasons as why
from kinect_agent.analysis.reasons import Reason

KNEE_ELBOW_LIMIT_DEG = 170.0  # flexion of the joint centres no knee or elbow passes
HIP_LIMIT_DEG = 190.0  # the thigh 10° past the trunk's axis: no hip on mocap passes 181.1°
# {angle: the flexion no joint passes, degrees} (module doc)
FLEXION_LIMIT_DEG = {
    **{f"{joint}_flexion_{side}": KNEE_ELBOW_LIMIT_DEG for joint in ("knee", "elbow") for side in ("L", "R")},
    **{f"hip_flexion_{side}": HIP_LIMIT_DEG for side in ("L", "R")},
}
SIDE_SUFFIX = {"left": "_L", "right": "_R"}


class Counted(Protocol):
    """A counted repetition: its side ('left', 'right', 'both', 'center') and times, s from the first frame."""

    @property
    def side(self) -> str: ...
    @property
    def start_s(self) -> float: ...
    @property
    def end_s(self) -> float: ...
    @property
    def peak_s(self) -> float: ...


def own_angles(names: tuple[str, ...], side: str) -> list[str]:
    """Returns the angles among `names` a repetition of `side` is measured on: its side's, or all for 'both' and
    'center' (and for a side none of them has)."""
    suffix = SIDE_SUFFIX.get(side)
    return [n for n in names if suffix is not None and n.endswith(suffix)] or list(names)


def repetition_frames(t: np.ndarray, rep: Counted) -> np.ndarray:
    """Returns the frame indices (n,) of a repetition, start to end, its peak frame among them; t: (T,) s."""
    rel = t - t[0]
    k = int(np.clip(np.searchsorted(rel, rep.peak_s - 1e-9), 0, t.shape[0] - 1))
    first, last = np.searchsorted(rel, [rep.start_s - 1e-9, rep.end_s + 1e-9])
    return np.arange(min(int(first), k), max(int(last), k + 1))


def limit_reason(name: str, top: float | None) -> Reason | None:
    """Returns beyond_anatomy when `top` (degrees) of angle `name` passes its FLEXION_LIMIT_DEG, else None (also for
    an angle without a limit or an unknown top)."""
    limit = FLEXION_LIMIT_DEG.get(name)
    if limit is None or top is None or not np.isfinite(top) or top <= limit:
        return None
    return why.BEYOND_ANATOMY.reason(reached=round(top), limit=round(limit))


def repetition_beyond_anatomy(
    t: np.ndarray, angles: dict[str, np.ndarray], names: tuple[str, ...], rep: Counted
) -> Reason | None:
    """Returns beyond_anatomy when a curve the repetition's peak is measured on (angles: {name: (T,) degrees}, the
    measured angles; its side's among the defining `names`, report.measured_peak) passes its flexion limit within
    the repetition's frames (t: (T,) s), with the highest such value; else None."""
    frames = repetition_frames(t, rep)
    found: list[Reason] = []
    for name in own_angles(names, rep.side):
        if name not in angles or name not in FLEXION_LIMIT_DEG or frames.size == 0:
            continue
        values = np.asarray(angles[name], dtype=np.float64)[frames]
        top = float(np.nanmax(values)) if np.isfinite(values).any() else None
        reason = limit_reason(name, top)
        if reason is not None:
            found.append(reason)
    return max(found, key=lambda r: float(r.params["reached"]), default=None)


def rom_beyond_anatomy(withheld: list[Reason | None]) -> Reason | None:
    """Returns why the session's range of motion (the median repetition amplitude) is withheld: repetitions_beyond_
    anatomy when any of the repetitions (their beyond_anatomy reasons, None where shown) is withheld, with how many
    and the highest flexion reached; None when every one is shown."""
    found = [r for r in withheld if r is not None]
    if not found:
        return None
    top = max(found, key=lambda r: float(r.params["reached"]))
    return why.REPETITIONS_BEYOND_ANATOMY.reason(
        withheld=len(found), count=len(withheld), reached=float(top.params["reached"]), limit=float(top.params["limit"])
    )
