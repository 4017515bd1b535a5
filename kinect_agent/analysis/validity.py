"""Which of a session's metrics the recording device can support, with the reason in words when it cannot.

A depth camera (Kinect v1/v2, Azure Kinect, Orbbec Femto) measures every joint in 3D: all metrics are valid. An
ordinary camera (device "webcam") sees the image plane well and depth poorly: the distance of each joint to the
camera comes from the pose model's body-shape prior and the hips' distance from an assumed field of view
(kinect_agent.sources.webcam.mapping). So, for "webcam":
- repetitions and time-based figures (moving time, tempo): valid, they need only the angle's rise and fall;
- a joint angle whose movement lies in a plane facing the camera (IN_PLANE below, by the view): valid;
- an angle whose movement goes towards or away from the camera (out of plane), and the shoulder's rotation (about the
  upper arm, never in the image plane): flagged, "out_of_plane";
- metres and arm lengths (reach and workspace, sway and balance, joint paths): flagged, "metric_scale".
The view comes from the recording itself (view_of): the trunk's forward direction against the camera's axis.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from kinect_agent.body.angles import ANGLE_NAMES, body_frame

MONOCULAR_DEVICES = ("webcam",)
VIEWS = ("front", "side", "oblique", "unknown")
FRONT_MAX_DEG, SIDE_MIN_DEG = 30.0, 60.0  # the trunk's forward axis this far from the camera's axis

# the anatomical plane each angle moves in ("sagittal": forward-up, seen from the side; "frontal": sideways-up,
# seen from the front; "transverse": about a limb's own axis, never seen in the image plane)
PLANE: dict[str, str] = {
    "elbow_flexion_L": "sagittal", "elbow_flexion_R": "sagittal",
    "knee_flexion_L": "sagittal", "knee_flexion_R": "sagittal",
    "shoulder_flexion_L": "sagittal", "shoulder_flexion_R": "sagittal",
    "shoulder_abduction_L": "frontal", "shoulder_abduction_R": "frontal",
    "shoulder_rotation_L": "transverse", "shoulder_rotation_R": "transverse",
    "hip_flexion_L": "sagittal", "hip_flexion_R": "sagittal",
    "hip_abduction_L": "frontal", "hip_abduction_R": "frontal",
    "trunk_flexion": "sagittal", "trunk_lateral_flexion": "frontal",
}  # fmt: skip
IN_PLANE = {"side": "sagittal", "front": "frontal"}  # the plane that faces the camera in each view
SCALE_METRICS = ("workspace", "balance", "joint_paths")  # figures in metres or arm lengths
TIME_METRICS = ("repetitions", "moving_time", "tempo")

REASONS = {
    "out_of_plane": "This angle moves towards and away from the camera. One ordinary camera measures depth poorly, "
    "so the angle can be off by tens of degrees. Film the exercise from the {want} to measure it.",
    "transverse": "A turn about the arm's own axis cannot be seen in a camera image.",
    "unknown_view": "The view could not be told from the recording, so this angle may lie out of the image plane.",
    "metric_scale": "Distances in metres come from an assumed camera and an average body size, not from a depth "
    "sensor: compare them only between sessions filmed the same way.",
}


DEVICE_LABELS = {
    "kinect1": "Kinect v1", "kinect2": "Kinect v2", "azure_kinect": "Azure Kinect", "femto": "Orbbec Femto",
    "mocap": "motion capture", "simulator": "simulated camera", "webcam": "ordinary camera (webcam)",
    "unknown": "unknown device",
}  # fmt: skip


def device_label(device: str) -> str:
    """Returns the device's name in words (the code itself when unknown)."""
    return DEVICE_LABELS.get(device, device)


def recorded_with(device: str, extra: dict[str, Any] | None) -> dict[str, Any]:
    """Returns what recorded a session, for pages and exports: {"device", "label", "model", "model_sha256",
    "runtime", "fps_achieved"} (None where the recording does not say; the model fields come from the webcam's
    header, kinect_agent.sources.webcam)."""
    found = extra.get("webcam") if isinstance(extra, dict) else None
    webcam: dict[str, Any] = found if isinstance(found, dict) else {}
    model: dict[str, Any] = webcam["model"] if isinstance(webcam.get("model"), dict) else {}
    fps = webcam.get("fps_achieved")

    def text(value: object) -> str | None:
        return value[:200] if isinstance(value, str) else None

    return {
        "device": device,
        "label": device_label(device),
        "model": text(model.get("name")),
        "model_sha256": text(model.get("sha256")),
        "runtime": text(webcam.get("runtime")),
        "fps_achieved": float(fps) if isinstance(fps, int | float) and not isinstance(fps, bool) else None,
    }


@dataclass(frozen=True)
class MetricValidity:
    """Whether one metric is valid for the device and view; code and reason (plain words) when it is not."""

    name: str
    valid: bool
    code: str | None = None
    reason: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """Returns the fields as JSON-ready data."""
        return {"name": self.name, "valid": self.valid, "code": self.code, "reason": self.reason}


@dataclass(frozen=True)
class SessionValidity:
    """The validity of every metric of one session: device, view (VIEWS), the trunk's angle to the camera axis."""

    device: str
    view: str
    view_deg: float | None
    metrics: dict[str, MetricValidity] = field(default_factory=dict)

    @property
    def limited(self) -> bool:
        """Whether any metric is flagged."""
        return any(not m.valid for m in self.metrics.values())

    def to_dict(self) -> dict[str, Any]:
        """Returns {"device", "view", "view_deg", "limited", "metrics": [...]} (JSON-ready)."""
        return {"device": self.device, "view": self.view, "view_deg": self.view_deg, "limited": self.limited,
                "metrics": [m.to_dict() for m in self.metrics.values()]}  # fmt: skip


def view_of(positions: np.ndarray) -> tuple[str, float | None]:
    """Returns (view, degrees) of a recording: the median angle between the trunk's horizontal forward axis and the
    camera's axis, 0 facing (or turning its back to) the camera, 90 side on.

    positions: (T, J, 3) m, camera frame (y up, z away from the camera), NaN = untracked.
    """
    _, _, forward = body_frame(np.asarray(positions, dtype=np.float64))
    horizontal = forward[..., [0, 2]]
    ok = np.all(np.isfinite(horizontal), axis=-1) & (np.linalg.norm(horizontal, axis=-1) > 0.3)
    if ok.sum() < 5:
        return "unknown", None
    h = horizontal[ok]
    deg = np.degrees(np.arctan2(np.abs(h[:, 0]), np.abs(h[:, 1])))  # 0: along z, 90: along x
    median = float(np.median(deg))
    view = "front" if median <= FRONT_MAX_DEG else "side" if median >= SIDE_MIN_DEG else "oblique"
    return view, round(median, 1)


def angle_validity(device: str, view: str, angle: str) -> MetricValidity:
    """Returns the validity of one clinical angle (ANGLE_NAMES) for a device and view."""
    if angle not in PLANE:
        raise ValueError(f"unknown angle {angle!r}; known: {', '.join(ANGLE_NAMES)}")
    if device not in MONOCULAR_DEVICES:
        return MetricValidity(angle, True)
    plane = PLANE[angle]
    if plane == "transverse":
        return MetricValidity(angle, False, "out_of_plane", REASONS["transverse"])
    if view not in IN_PLANE:
        return MetricValidity(angle, False, "out_of_plane", REASONS["unknown_view"])
    if IN_PLANE[view] == plane:
        return MetricValidity(angle, True)
    want = "side" if plane == "sagittal" else "front"
    return MetricValidity(angle, False, "out_of_plane", REASONS["out_of_plane"].format(want=want))


def session_validity(device: str, positions: np.ndarray | None, angles: tuple[str, ...] = ANGLE_NAMES,
                     defining_angle: str | None = None) -> SessionValidity:  # fmt: skip
    """Returns the validity of a session's metrics.

    device: the recording's device (kinect_agent.recording.DEVICES); positions: (T, J, 3) m camera frame, used for
    the view (None: unknown); angles: the angles shown; defining_angle: the angle of the range of motion ("rom"
    follows it; None: the first of `angles`).
    """
    view, view_deg = view_of(positions) if positions is not None else ("unknown", None)
    metrics: dict[str, MetricValidity] = {name: MetricValidity(name, True) for name in TIME_METRICS}
    for angle in angles:
        metrics[angle] = angle_validity(device, view, angle)
    rom_angle = defining_angle or (angles[0] if angles else None)
    if rom_angle is not None:
        base = metrics.get(rom_angle) or angle_validity(device, view, rom_angle)
        metrics["rom"] = MetricValidity("rom", base.valid, base.code, base.reason)
    for name in SCALE_METRICS:
        ok = device not in MONOCULAR_DEVICES
        metrics[name] = MetricValidity(
            name, ok, None if ok else "metric_scale", None if ok else REASONS["metric_scale"]
        )
    return SessionValidity(device, view, view_deg, metrics)
