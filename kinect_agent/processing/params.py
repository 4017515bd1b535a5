"""KinematicParams: the filter's output in kinematic form (segment lengths, root, rotations, angles) and its JSON form.

Rotations follow kinect_agent.body.kinematics.forward_kinematics_quat with the module's REST_DIRECTIONS, so
`forward_kinematics_quat(root, q_root, segment_lengths, q_local)` rebuilds the filtered joint positions.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body.angles import ANGLE_NAMES
from kinect_agent.body.kinematics import N_BONES, forward_kinematics_quat

FORMAT = "kinect-home-coach/kinematic-params"
VERSION = 1


@dataclass
class KinematicParams:
    """Kinematic parameters of one recording.

    t: (T,) s. segment_lengths: (19,) m, BONES order (constant over the recording).
    root: (T, 3) m, ROOT position, camera frame. q_root: (T, 4) wxyz, ROOT body frame (x left, y up, z forward)
    -> camera frame. q_local: (T, 19, 4) wxyz, each bone's rotation relative to the bone entering its parent joint.
    joint_angles: name -> (T,) degrees, angles.joint_angles of the positions these parameters rebuild.
    outlier_prob: (T, J) in [0, 1], probability that the input sample was a tracking-loss outlier.
    """

    t: np.ndarray
    segment_lengths: np.ndarray
    root: np.ndarray
    q_root: np.ndarray
    q_local: np.ndarray
    joint_angles: dict[str, np.ndarray] = field(default_factory=dict)
    outlier_prob: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.t = np.asarray(self.t, dtype=np.float64)
        T = self.t.shape[0]
        expect = {
            "segment_lengths": (N_BONES,),
            "root": (T, 3),
            "q_root": (T, 4),
            "q_local": (T, N_BONES, 4),
        }
        for name, shape in expect.items():
            value = np.asarray(getattr(self, name), dtype=np.float64)
            if value.shape != shape:
                raise ValueError(f"{name} must have shape {shape}, got {value.shape}")
            setattr(self, name, value)
        if self.outlier_prob is None:
            self.outlier_prob = np.zeros((T, skeleton.J))
        self.outlier_prob = np.asarray(self.outlier_prob, dtype=np.float64)
        if self.outlier_prob.shape != (T, skeleton.J):
            raise ValueError(f"outlier_prob must have shape {(T, skeleton.J)}, got {self.outlier_prob.shape}")
        self.joint_angles = {k: np.asarray(v, dtype=np.float64) for k, v in self.joint_angles.items()}
        for k, v in self.joint_angles.items():
            if v.shape != (T,):
                raise ValueError(f"joint_angles[{k!r}] must have shape ({T},), got {v.shape}")

    @property
    def n_frames(self) -> int:
        """Number of frames T."""
        return int(self.t.shape[0])

    def positions(self) -> np.ndarray:
        """Returns the joint positions (T, J, 3) m, camera frame, rebuilt by forward kinematics."""
        lengths = np.broadcast_to(self.segment_lengths, (self.n_frames, N_BONES))
        return forward_kinematics_quat(self.root, self.q_root, lengths, self.q_local)

    def to_json(self) -> dict[str, Any]:
        """Returns JSON-ready data: lists of floats rounded to 0.1 mm, 1e-5 (quaternions), 0.01° and 1e-3."""
        return {
            "format": FORMAT,
            "version": VERSION,
            "joints": list(skeleton.JOINTS),
            "bones": [[skeleton.JOINTS[p], skeleton.JOINTS[c]] for p, c in skeleton.BONES],
            "t": np.round(self.t, 6).tolist(),
            "segment_lengths_m": np.round(self.segment_lengths, 5).tolist(),
            "root_m": np.round(self.root, 5).tolist(),
            "q_root_wxyz": np.round(self.q_root, 5).tolist(),
            "q_local_wxyz": np.round(self.q_local, 5).tolist(),
            "joint_angles_deg": {k: _nan_list(np.round(v, 2)) for k, v in self.joint_angles.items()},
            "outlier_prob": np.round(self.outlier_prob, 3).tolist(),
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> KinematicParams:
        """Builds parameters from `to_json` output; raises ValueError naming the missing or malformed field."""
        if not isinstance(data, dict) or data.get("format") != FORMAT:
            raise ValueError(f"not a kinematic-parameters document: 'format' must be {FORMAT!r}")
        if data.get("version") != VERSION:
            raise ValueError(f"unsupported kinematic-parameters version {data.get('version')!r}; expected {VERSION}")
        try:
            return cls(
                t=np.array(data["t"], dtype=np.float64),
                segment_lengths=np.array(data["segment_lengths_m"], dtype=np.float64),
                root=np.array(data["root_m"], dtype=np.float64),
                q_root=np.array(data["q_root_wxyz"], dtype=np.float64),
                q_local=np.array(data["q_local_wxyz"], dtype=np.float64),
                joint_angles={
                    k: np.array([np.nan if v is None else v for v in vals], dtype=np.float64)
                    for k, vals in data.get("joint_angles_deg", {}).items()
                },
                outlier_prob=np.array(data["outlier_prob"], dtype=np.float64) if "outlier_prob" in data else None,
            )
        except KeyError as exc:
            raise ValueError(f"kinematic-parameters document lacks the field {exc.args[0]!r}") from None
        except (TypeError, ValueError) as exc:
            raise ValueError(f"malformed kinematic-parameters document: {exc}") from None


def _nan_list(v: np.ndarray) -> list[float | None]:
    return [None if not np.isfinite(x) else float(x) for x in v]


__all__ = ["ANGLE_NAMES", "KinematicParams"]
