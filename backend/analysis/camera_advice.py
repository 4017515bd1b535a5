"""Camera advice in plain words, estimated from where the body was in the camera's view during a session.

Positions are in the Kinect camera frame (metres; x to the side, y up, z away from the camera). Checks, each giving
one piece of advice with a code:
    too_close / too_far   the trunk's distance z (median over frames of ROOT and SPINE) below NEAR_M (1.5 m) or
                          above FAR_M (3.8 m); the skeleton is tracked best from about 2 to 3 m;
    off_centre            the trunk's horizontal angle atan(|x| / z) above OFF_CENTRE_FRAC (0.5) of half the
                          camera's horizontal field of view (Kinect 2: 70°, Kinect 1: 57°);
    hand_out_of_view,     the hand (foot) of one side was out of view in more than OUT_OF_VIEW (20 %) of the frames:
    foot_out_of_view      not tracked, or inferred together with its wrist (ankle) - the sensor infers both when the
                          limb leaves the picture, while a hand inferred alone (UI-PRMD has no hand joint) is not;
    feet_cut_off          the feet (95th percentile of their angle below the optical axis, atan(−y / z)) within
                          EDGE_MARGIN_DEG (3°) of the bottom of the vertical field of view (Kinect 2: 60°, Kinect 1:
                          43°).
A camera tilted up or down shifts the vertical angles; the advice says "about" for that reason.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from kinect_agent.recording import Recording
from kinect_agent.skeleton import INDEX, NOT_TRACKED, TRACKED

NEAR_M = 1.5
FAR_M = 3.8
OFF_CENTRE_FRAC = 0.5
OUT_OF_VIEW = 0.2
EDGE_MARGIN_DEG = 3.0
# device -> (horizontal, vertical) field of view of the depth camera, degrees
FIELD_OF_VIEW = {"kinect1": (57.0, 43.0), "kinect2": (70.0, 60.0), "azure_kinect": (75.0, 65.0)}
DEFAULT_FOV = FIELD_OF_VIEW["kinect2"]
_LIMBS = (("hand", "HAN", "WRI"), ("foot", "FOO", "ANK"))
_SIDES = (("left", "L"), ("right", "R"))


def _trunk(raw: Recording) -> np.ndarray:
    """Returns (K, 3) m: the ROOT and SPINE positions of the frames where they were seen."""
    idx = [INDEX["ROOT"], INDEX["SPINE"]]
    seen = raw.state[:, idx] != NOT_TRACKED
    points = raw.positions[:, idx][seen]
    return points[np.all(np.isfinite(points), axis=1)]


def distance_advice(trunk: np.ndarray) -> list[dict[str, Any]]:
    """Returns too_close / too_far advice from trunk positions (K, 3) m, camera frame."""
    if trunk.shape[0] == 0:
        return []
    z = float(np.median(trunk[:, 2]))
    if z < NEAR_M:
        return [
            {
                "code": "too_close",
                "text": f"You were about {z:.1f} m from the camera, which is too close for it to "
                "see your whole body. Stand further back, about 2 to 3 m away.",
            }
        ]
    if z > FAR_M:
        return [
            {
                "code": "too_far",
                "text": f"You were about {z:.1f} m from the camera, which is far for it to see you "
                "clearly. Come closer, to about 2 to 3 m away.",
            }
        ]
    return []


def centre_advice(trunk: np.ndarray, fov_h_deg: float) -> list[dict[str, Any]]:
    """Returns off_centre advice from trunk positions (K, 3) m and the horizontal field of view (degrees)."""
    if trunk.shape[0] == 0:
        return []
    x, z = float(np.median(trunk[:, 0])), float(np.median(trunk[:, 2]))
    if z <= 0 or np.degrees(np.arctan(abs(x) / z)) <= OFF_CENTRE_FRAC * fov_h_deg / 2:
        return []
    return [
        {
            "code": "off_centre",
            "text": f"You were about {abs(x):.1f} m to one side of the middle of the camera's "
            "view. Stand in the middle, or turn the camera towards where you exercise.",
        }
    ]


def out_of_view_fractions(raw: Recording) -> dict[tuple[str, str], float]:
    """Returns {(limb, side): fraction of frames the hand or foot was out of view} (module doc)."""
    out = {}
    for limb, end, base in _LIMBS:
        for side, s in _SIDES:
            e, b = raw.state[:, INDEX[f"{end}_{s}"]], raw.state[:, INDEX[f"{base}_{s}"]]
            lost = (e == NOT_TRACKED) | ((e != TRACKED) & (b != TRACKED))
            out[(limb, side)] = float(lost.mean()) if lost.size else 0.0
    return out


def limb_advice(raw: Recording) -> list[dict[str, Any]]:
    """Returns hand_out_of_view / foot_out_of_view advice naming the sides that left the picture."""
    out = []
    fractions = out_of_view_fractions(raw)
    for limb, _, _ in _LIMBS:
        sides = [side for side, _ in _SIDES if fractions[(limb, side)] > OUT_OF_VIEW]
        if not sides:
            continue
        worst = max(fractions[(limb, side)] for side in sides)
        which = f"both {limb}s" if len(sides) == 2 else f"your {sides[0]} {limb}"
        out.append(
            {
                "code": f"{limb}_out_of_view",
                "text": f"The camera lost {which} in about {worst:.0%} of the "
                f"recording. Make sure your whole body, {limb}s included, fits in the picture while you move: "
                "step back a little or point the camera at the middle of your body.",
            }
        )
    return out


def feet_advice(raw: Recording, fov_v_deg: float) -> list[dict[str, Any]]:
    """Returns feet_cut_off advice when the feet sit at the bottom edge of the vertical field of view (degrees)."""
    idx = [INDEX["FOO_L"], INDEX["FOO_R"]]
    feet = raw.positions[:, idx][raw.state[:, idx] != NOT_TRACKED]
    feet = feet[np.all(np.isfinite(feet), axis=1) & (feet[:, 2] > 0)] if feet.size else feet.reshape(0, 3)
    if feet.shape[0] == 0:
        return []
    below = np.degrees(np.arctan2(-feet[:, 1], feet[:, 2]))
    if float(np.percentile(below, 95)) < fov_v_deg / 2 - EDGE_MARGIN_DEG:
        return []
    return [
        {
            "code": "feet_cut_off",
            "text": "Your feet were at the bottom edge of the picture. Tilt the camera down "
            "a little, or place it further away, so that your feet are well inside the view.",
        }
    ]


def camera_advice(raw: Recording) -> list[dict[str, Any]]:
    """Returns [{"code", "text"}]: plain-words advice on the camera set-up of a raw recording (module doc)."""
    fov_h, fov_v = FIELD_OF_VIEW.get(raw.meta.device, DEFAULT_FOV)
    trunk = _trunk(raw)
    return distance_advice(trunk) + centre_advice(trunk, fov_h) + limb_advice(raw) + feet_advice(raw, fov_v)
