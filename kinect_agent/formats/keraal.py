"""KERAAL Kinect v2 skeleton files (Devanne, Nguyen et al.; readme_files_format.txt section 2).

One frame per line: 25 joints in Kinect v2 SDK order, each x y z (metres, Kinect camera space, y up)
then the joint orientation quaternion qx qy qz qw: 175 whitespace-separated numbers. The files carry
no time stamps, so t = i / 30 s (the Kinect v2 rate), flagged by meta.extra["rate_assumed"] = True.
The quaternions are dropped (Recording has no orientation channel; they are all zero in the
kinect_gmm_examples files), meta.extra["orientations_present"] says whether any were non-zero. An
all-zero position is read as not tracked.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from kinect_agent.formats import kinect_joints
from kinect_agent.recording import Metadata, Recording

NAME = "keraal"
DESCRIPTION = "KERAAL Kinect v2 text (25 joints x y z qx qy qz qw per line, 30 Hz assumed)"
RATE_HZ = 30.0
N_JOINTS = 25
FIELDS_PER_JOINT = 7
N_FIELDS = N_JOINTS * FIELDS_PER_JOINT


def sniff(path: Path, head: bytes) -> bool:
    """True when the first line holds 175 numbers."""
    cells = kinect_joints.first_line_fields(head)
    return cells is not None and len(cells) == N_FIELDS


def read(path: Path) -> Recording:
    """Reads a KERAAL Kinect file into a kinect2 recording at an assumed 30 Hz; FormatError names file and line."""
    path = Path(path)
    values, _, _ = kinect_joints.read_numeric_rows(path, N_FIELDS)
    joints = values.reshape(-1, N_JOINTS, FIELDS_PER_JOINT)
    raw = joints[:, :, :3].copy()
    raw[np.all(raw == 0.0, axis=-1)] = np.nan  # an all-zero position is the SDK's "not tracked"
    positions, state = kinect_joints.to_skeleton(raw, "kinect2")
    meta = Metadata(device="kinect2", rate_hz=RATE_HZ, source=str(path))
    meta.extra["rate_assumed"] = True
    meta.extra["orientations_present"] = bool(np.any(joints[:, :, 3:] != 0.0))
    parts = path.stem.split("-")
    if len(parts) >= 4 and parts[1].lower() == "kinect":
        meta.exercise, meta.extra["group"], meta.extra["recording"] = parts[2], parts[0], path.stem
        meta.subject = parts[3]
    elif path.stem.lower().startswith("skeletonsequence"):
        meta.extra["sequence_dir"] = path.parent.name
    t = np.arange(len(values)) / RATE_HZ
    return Recording(t, positions, state, meta)
