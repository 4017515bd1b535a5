"""The 20-joint skeleton of Wang et al. (remote health coaching with Kinect), declared once.

Everything else (formats, simulator, filters, metrics) derives its joint order, bones and
segments from the tables below.

Frame convention for all positions in this project: metres, right-handed camera frame with
x to the side, y up and z pointing away from the camera (Kinect camera space).
"""

from __future__ import annotations

import numpy as np

JOINTS: tuple[str, ...] = (
    "ROOT", "SPINE", "NECK", "HEAD",
    "SHO_L", "ELB_L", "WRI_L", "HAN_L",
    "SHO_R", "ELB_R", "WRI_R", "HAN_R",
    "HIP_L", "KNE_L", "ANK_L", "FOO_L",
    "HIP_R", "KNE_R", "ANK_R", "FOO_R",
)  # fmt: skip
J = len(JOINTS)
INDEX: dict[str, int] = {name: i for i, name in enumerate(JOINTS)}

PARENT_NAME: dict[str, str | None] = {
    "ROOT": None, "SPINE": "ROOT", "NECK": "SPINE", "HEAD": "NECK",
    "SHO_L": "NECK", "ELB_L": "SHO_L", "WRI_L": "ELB_L", "HAN_L": "WRI_L",
    "SHO_R": "NECK", "ELB_R": "SHO_R", "WRI_R": "ELB_R", "HAN_R": "WRI_R",
    "HIP_L": "ROOT", "KNE_L": "HIP_L", "ANK_L": "KNE_L", "FOO_L": "ANK_L",
    "HIP_R": "ROOT", "KNE_R": "HIP_R", "ANK_R": "KNE_R", "FOO_R": "ANK_R",
}  # fmt: skip
# PARENT[j]: index of the parent of joint j, -1 for ROOT. Parents come before children.
PARENT: np.ndarray = np.array([-1 if (p := PARENT_NAME[n]) is None else INDEX[p] for n in JOINTS])

# Rotational degrees of freedom of each joint (paper, section 4): the rotation of the bones that
# leave joint j, relative to the bone that enters it. ROOT carries the global orientation (and the
# global position, 3 more). HEAD, HAN_* and FOO_* are leaves: no bone leaves them, so 0.
DOF: dict[str, int] = {
    "ROOT": 3, "SPINE": 3, "NECK": 3, "HEAD": 0,
    "SHO_L": 3, "ELB_L": 1, "WRI_L": 2, "HAN_L": 0,
    "SHO_R": 3, "ELB_R": 1, "WRI_R": 2, "HAN_R": 0,
    "HIP_L": 3, "KNE_L": 1, "ANK_L": 2, "FOO_L": 0,
    "HIP_R": 3, "KNE_R": 1, "ANK_R": 2, "FOO_R": 0,
}  # fmt: skip

# The 19 bones as (parent, child) joint indices, in joint order of the child.
BONES: tuple[tuple[int, int], ...] = tuple((int(PARENT[c]), c) for c in range(1, J))

# The 14 segments of the paper's accuracy tables: name -> (proximal joint, distal joint).
SEGMENTS: dict[str, tuple[str, str]] = {
    "ARM_UP_L": ("SHO_L", "ELB_L"), "ARM_LO_L": ("ELB_L", "WRI_L"), "HAND_L": ("WRI_L", "HAN_L"),
    "ARM_UP_R": ("SHO_R", "ELB_R"), "ARM_LO_R": ("ELB_R", "WRI_R"), "HAND_R": ("WRI_R", "HAN_R"),
    "PELVIC_L": ("ROOT", "HIP_L"), "LEG_UP_L": ("HIP_L", "KNE_L"), "LEG_LO_L": ("KNE_L", "ANK_L"),
    "FOOT_L": ("ANK_L", "FOO_L"),
    "PELVIC_R": ("ROOT", "HIP_R"), "LEG_UP_R": ("HIP_R", "KNE_R"), "LEG_LO_R": ("KNE_R", "ANK_R"),
    "FOOT_R": ("ANK_R", "FOO_R"),
}  # fmt: skip
SEGMENT_NAMES: tuple[str, ...] = tuple(SEGMENTS)
SEGMENT_JOINTS: np.ndarray = np.array([[INDEX[a], INDEX[b]] for a, b in SEGMENTS.values()])  # (14, 2)

# Tracking state codes, as the Kinect SDK reports them.
NOT_TRACKED, INFERRED, TRACKED = 0, 1, 2


def bone_lengths(positions: np.ndarray) -> np.ndarray:
    """Returns the length of every bone per frame.

    positions: (..., J, 3) float, metres, any frame; NaN = untracked.
    returns: (..., J-1) float, metres, bone k joins BONES[k]; NaN where an end is untracked.
    """
    parents = PARENT[1:]
    return np.linalg.norm(positions[..., 1:, :] - positions[..., parents, :], axis=-1)


def segment_lengths(positions: np.ndarray) -> np.ndarray:
    """Returns the length of the 14 named segments per frame.

    positions: (..., J, 3) float, metres, any frame; NaN = untracked.
    returns: (..., 14) float, metres, in SEGMENT_NAMES order; NaN where an end is untracked.
    """
    a, b = SEGMENT_JOINTS[:, 0], SEGMENT_JOINTS[:, 1]
    return np.linalg.norm(positions[..., b, :] - positions[..., a, :], axis=-1)


def mirror_name(name: str) -> str:
    """Returns the name of the joint or segment on the other side (itself when central)."""
    if name.endswith("_L"):
        return name[:-2] + "_R"
    if name.endswith("_R"):
        return name[:-2] + "_L"
    return name
