"""Any recording (optical mocap above all) as the exact truth a simulated Kinect measures.

The accuracy benchmark and `kinect-agent simulate --from FILE` both put a recorded motion in front of a simulated
camera: resampled to the Kinect's rate, gaps bridged, turned to face the camera (and by the view angle more) and
placed as kinect_agent.sources.motions places simulated subjects.
"""

from __future__ import annotations

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body.rotations import axis_rotation
from kinect_agent.formats.amc import facing_deg
from kinect_agent.recording import Recording
from kinect_agent.sources.kinect_noise import SimulationError
from kinect_agent.sources.motions import CAMERA_HEIGHT_M, SUBJECT_DISTANCE_M

_FEET = [skeleton.INDEX[n] for n in ("FOO_L", "FOO_R", "ANK_L", "ANK_R")]


def resample(rec: Recording, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Returns (t (N,) s from 0, positions (N, J, 3) m): rec linearly interpolated onto a rate_hz grid.

    Missing joint-frames (NaN) are bridged by interpolation in time (held flat before the first and after the last
    seen frame). Raises SimulationError when a joint is never seen.
    """
    flat = rec.positions.reshape(rec.n_frames, -1)
    seen = np.isfinite(flat)
    never = ~seen.any(axis=0)
    if never.any():
        joints = sorted({skeleton.JOINTS[c // 3] for c in np.flatnonzero(never)})
        raise SimulationError(f"joints {', '.join(joints)} are never present; they cannot serve as truth")
    t = np.arange(0.0, rec.duration + 1e-9, 1.0 / rate_hz) + rec.t[0]
    out = np.stack([np.interp(t, rec.t[seen[:, c]], flat[seen[:, c], c]) for c in range(flat.shape[1])], axis=1)
    return t - t[0], out.reshape(len(t), skeleton.J, 3)


def heading_deg(positions: np.ndarray) -> float:
    """Returns the subject's median heading over the first second, degrees about +y from +z (180 = facing −z).

    positions: (T, J, 3) m, y up, all finite, 30 Hz or so.
    """
    first = positions[: min(len(positions), 30)]
    angles = np.radians([facing_deg(frame) for frame in first])
    return float(np.degrees(np.arctan2(np.median(np.sin(angles)), np.median(np.cos(angles)))))


def place_in_camera(positions: np.ndarray, view_deg: float, facing: float) -> np.ndarray:
    """Returns positions (T, J, 3) m moved into the Kinect camera frame.

    positions: (T, J, 3) m, any world frame with y up, the subject heading `facing` degrees about +y from +z.
    The subject is turned to face the camera (−z) and by view_deg more, feet on the floor CAMERA_HEIGHT_M below
    the camera, the mean pelvis SUBJECT_DISTANCE_M in front of it.
    """
    R = axis_rotation(1, np.radians(180.0 + view_deg - facing))
    p = positions @ R.T
    floor = np.nanpercentile(p[:, _FEET, 1], 1)
    centre = np.nanmean(p[:, skeleton.INDEX["ROOT"]], axis=0)
    return p + np.array([-centre[0], -CAMERA_HEIGHT_M - floor, SUBJECT_DISTANCE_M - centre[2]])


def truth_from_recording(rec: Recording, *, view_deg: float, rate_hz: float = 30.0) -> Recording:
    """Returns rec as an exact truth recording in the camera frame at rate_hz, every joint in every frame."""
    if rec.n_frames < 2:
        raise SimulationError(f"the recording has {rec.n_frames} frame(s); a truth needs at least 2")
    t, p = resample(rec, rate_hz)
    truth = Recording.from_positions(t, place_in_camera(p, view_deg, heading_deg(p)))
    truth.meta.rate_hz = rate_hz
    truth.meta.subject = rec.meta.subject
    truth.meta.exercise = rec.meta.exercise
    return truth
