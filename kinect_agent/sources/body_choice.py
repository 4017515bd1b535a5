"""Which of the bodies a depth camera reports is the patient.

A Kinect v2 tracks up to six people, the Azure Kinect body tracker any number; a family member crossing the room, or
sitting on the sofa behind, must never become the recorded patient. The rule, per frame:
    follow    the body being recorded keeps being recorded while the camera still reports its tracking id;
    choose    otherwise (the first frame, or the patient left the view) the candidates are the bodies tracked for at
              least STABLE_FRAMES frames in a row (a ghost or a person walking past appears for a moment), or all
              bodies when none is yet; of them, the one with the smallest |x| + DEPTH_WEIGHT * z of its ROOT joint
              (camera space, m): the person centred in front of the camera, the nearer of two equally centred.
Bodies without a tracked ROOT are never chosen.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from kinect_agent import skeleton

STABLE_FRAMES = 15  # half a second at 30 Hz
DEPTH_WEIGHT = 0.25  # metres of lateral offset one metre of distance is worth
_ROOT = skeleton.INDEX["ROOT"]


@dataclass(frozen=True)
class Body:
    """One body of one frame: the SDK's tracking id, positions (J, 3) m camera space (NaN = missing), state (J,)."""

    tracking_id: int
    positions: np.ndarray
    state: np.ndarray


@dataclass
class PatientChooser:
    """Picks the patient among each frame's bodies (module docstring); keeps the followed id and how long each id
    has been seen in a row."""

    following: int | None = None
    streak: dict[int, int] = field(default_factory=dict)

    def choose(self, bodies: list[Body]) -> Body | None:
        """Returns the patient's body of this frame, or None when no body has a tracked ROOT."""
        present = [b for b in bodies if b.state[_ROOT] != skeleton.NOT_TRACKED and _root_seen(b)]
        self.streak = {b.tracking_id: self.streak.get(b.tracking_id, 0) + 1 for b in present}
        followed = next((b for b in present if b.tracking_id == self.following), None)
        if followed is not None:
            return followed
        stable = [b for b in present if self.streak[b.tracking_id] >= STABLE_FRAMES]
        candidates = stable or present
        if not candidates:
            self.following = None
            return None
        chosen = min(candidates, key=_score)
        self.following = chosen.tracking_id if stable else None  # follow only a body known to be stable
        return chosen


def _root_seen(body: Body) -> bool:
    return bool(np.isfinite(body.positions[_ROOT]).all())


def _score(body: Body) -> float:
    x, _, z = body.positions[_ROOT]
    return float(abs(x) + DEPTH_WEIGHT * z)
