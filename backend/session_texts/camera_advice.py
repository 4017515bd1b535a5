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

from backend.i18n import N_, Translator, translator
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
ENGLISH = translator("en")
Advice = dict[str, Any]  # {"code", "params", "text"}


def _trunk(raw: Recording) -> np.ndarray:
    """Returns (K, 3) m: the ROOT and SPINE positions of the frames where they were seen."""
    idx = [INDEX["ROOT"], INDEX["SPINE"]]
    seen = raw.state[:, idx] != NOT_TRACKED
    points = raw.positions[:, idx][seen]
    return points[np.all(np.isfinite(points), axis=1)]


def distance_advice(trunk: np.ndarray) -> list[Advice]:
    """Returns too_close / too_far advice from trunk positions (K, 3) m, camera frame."""
    if trunk.shape[0] == 0:
        return []
    z = float(np.median(trunk[:, 2]))
    if z < NEAR_M:
        return [advice("too_close", distance_m=round(z, 2))]
    if z > FAR_M:
        return [advice("too_far", distance_m=round(z, 2))]
    return []


def centre_advice(trunk: np.ndarray, fov_h_deg: float) -> list[Advice]:
    """Returns off_centre advice from trunk positions (K, 3) m and the horizontal field of view (degrees)."""
    if trunk.shape[0] == 0:
        return []
    x, z = float(np.median(trunk[:, 0])), float(np.median(trunk[:, 2]))
    if z <= 0 or np.degrees(np.arctan(abs(x) / z)) <= OFF_CENTRE_FRAC * fov_h_deg / 2:
        return []
    return [advice("off_centre", distance_m=round(abs(x), 2))]


def out_of_view_fractions(raw: Recording) -> dict[tuple[str, str], float]:
    """Returns {(limb, side): fraction of frames the hand or foot was out of view} (module doc)."""
    out = {}
    for limb, end, base in _LIMBS:
        for side, s in _SIDES:
            e, b = raw.state[:, INDEX[f"{end}_{s}"]], raw.state[:, INDEX[f"{base}_{s}"]]
            lost = (e == NOT_TRACKED) | ((e != TRACKED) & (b != TRACKED))
            out[(limb, side)] = float(lost.mean()) if lost.size else 0.0
    return out


def limb_advice(raw: Recording) -> list[Advice]:
    """Returns hand_out_of_view / foot_out_of_view advice naming the sides that left the picture."""
    out = []
    fractions = out_of_view_fractions(raw)
    for limb, _, _ in _LIMBS:
        sides = [side for side, _ in _SIDES if fractions[(limb, side)] > OUT_OF_VIEW]
        if not sides:
            continue
        worst = max(fractions[(limb, side)] for side in sides)
        out.append(advice(f"{limb}_out_of_view", sides="both" if len(sides) == 2 else sides[0],
                          fraction=round(worst, 4)))  # fmt: skip
    return out


def feet_advice(raw: Recording, fov_v_deg: float) -> list[Advice]:
    """Returns feet_cut_off advice when the feet sit at the bottom edge of the vertical field of view (degrees)."""
    idx = [INDEX["FOO_L"], INDEX["FOO_R"]]
    feet = raw.positions[:, idx][raw.state[:, idx] != NOT_TRACKED]
    feet = feet[np.all(np.isfinite(feet), axis=1) & (feet[:, 2] > 0)] if feet.size else feet.reshape(0, 3)
    if feet.shape[0] == 0:
        return []
    below = np.degrees(np.arctan2(-feet[:, 1], feet[:, 2]))
    if float(np.percentile(below, 95)) < fov_v_deg / 2 - EDGE_MARGIN_DEG:
        return []
    return [advice("feet_cut_off")]


def camera_advice(raw: Recording) -> list[Advice]:
    """Returns [{"code", "params", "text"}]: the advice on the camera set-up of a raw recording (module doc), its
    text in English (advice_text writes it in the reader's language)."""
    fov_h, fov_v = FIELD_OF_VIEW.get(raw.meta.device, DEFAULT_FOV)
    trunk = _trunk(raw)
    return distance_advice(trunk) + centre_advice(trunk, fov_h) + limb_advice(raw) + feet_advice(raw, fov_v)


# the patient is the one who moves the camera or stands elsewhere: the advice speaks to them (catalogue `messages`)
_TOO_CLOSE = N_(
    "You were about %(distance)s m from the camera, which is too close for it to see your whole body. "
    "Stand further back, about 2 to 3 m away."
)
_TOO_FAR = N_(
    "You were about %(distance)s m from the camera, which is far for it to see you clearly. "
    "Come closer, to about 2 to 3 m away."
)
_OFF_CENTRE = N_(
    "You were about %(distance)s m to one side of the middle of the camera's view. "
    "Stand in the middle, or turn the camera towards where you exercise."
)
# (limb, sides) -> the sentence: a whole sentence each, as "both hands"/"your left hand" change the words around them
_OUT_OF_VIEW = {
    ("hand", "both"): N_(
        "The camera lost both hands in about %(share)s of the recording. Make sure your whole body, hands "
        "included, fits in the picture while you move: step back a little or point the camera at the middle of "
        "your body."
    ),
    ("hand", "left"): N_(
        "The camera lost your left hand in about %(share)s of the recording. Make sure your whole body, hands "
        "included, fits in the picture while you move: step back a little or point the camera at the middle of "
        "your body."
    ),
    ("hand", "right"): N_(
        "The camera lost your right hand in about %(share)s of the recording. Make sure your whole body, hands "
        "included, fits in the picture while you move: step back a little or point the camera at the middle of "
        "your body."
    ),
    ("foot", "both"): N_(
        "The camera lost both feet in about %(share)s of the recording. Make sure your whole body, feet "
        "included, fits in the picture while you move: step back a little or point the camera at the middle of "
        "your body."
    ),
    ("foot", "left"): N_(
        "The camera lost your left foot in about %(share)s of the recording. Make sure your whole body, feet "
        "included, fits in the picture while you move: step back a little or point the camera at the middle of "
        "your body."
    ),
    ("foot", "right"): N_(
        "The camera lost your right foot in about %(share)s of the recording. Make sure your whole body, feet "
        "included, fits in the picture while you move: step back a little or point the camera at the middle of "
        "your body."
    ),
}
_FEET_CUT_OFF = N_(
    "Your feet were at the bottom edge of the picture. Tilt the camera down a little, or place it further away, "
    "so that your feet are well inside the view."
)


def advice(code: str, **params: float | str) -> Advice:
    """Returns one piece of advice: its code, what it was found from (params) and its text in English."""
    return {"code": code, "params": params, "text": advice_text(code, params, ENGLISH)}


def advice_text(code: str, params: dict[str, Any], t: Translator) -> str:
    """Returns the text of one piece of advice (code and params as camera_advice gives them) in t's language, its
    numbers as t's locale writes them; raises KeyError for an unknown code or missing params."""
    if code in ("too_close", "too_far", "off_centre"):
        message = {"too_close": _TOO_CLOSE, "too_far": _TOO_FAR, "off_centre": _OFF_CENTRE}[code]
        return t.gettext(message, distance=t.format_number(float(params["distance_m"]), 1))
    if code in ("hand_out_of_view", "foot_out_of_view"):
        message = _OUT_OF_VIEW[(code.split("_")[0], str(params["sides"]))]
        return t.gettext(message, share=t.format_percent(float(params["fraction"])))
    if code == "feet_cut_off":
        return t.gettext(_FEET_CUT_OFF)
    raise KeyError(code)
