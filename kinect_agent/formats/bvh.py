"""BVH (Biovision hierarchy) optical motion capture reader, used as ground truth for benchmarks.

HIERARCHY: ROOT/JOINT/End Site blocks with OFFSET (file units, parent frame) and CHANNELS (any order
of X/Y/Zposition and X/Y/Zrotation, degrees). MOTION: `Frames: N`, `Frame Time: s`, then N rows.
Rotations compose intrinsically in the listed order: R_parent_joint = R(c1) @ R(c2) @ R(c3).
Forward kinematics is vectorised over frames and loops over joints only. Position channels on a joint (the root,
or every joint as some exporters write): where their values follow the OFFSET (their median is nearer the OFFSET
than zero) they are the joint's local position and replace it, as Blender reads them; where they stay near zero
they are a displacement added to it; values near neither are refused. Units: the thigh (hip to knee) of the first
frame must be 0.3-0.6 m in exactly one of CMU ASF units (inches / 0.45, i.e. 0.05644 m; CMU conversions), cm,
inches, m or mm (the ranges do not overlap), else 0.2-0.7 m (a child, a tall adult) in exactly one of them; a file
with no thigh, or with none or two fitting units (a 0.25 m thigh in cm is 0.64 m in inches) is refused. Joint names:
CMU, Mixamo (`mixamorig:` prefix), Unity, Xsens and `Left_Thigh` styles (mocap_mapping); the thigh must be found.
Output is metres in the file's world frame (y up, as BVH is; not rotated into a camera frame: in CMU 13_29 the
subject faces +z in frame 0 with their left at +x). Plain or gzip, any line ends, BOM (formats._text).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body.rotations import axis_rotation
from kinect_agent.errors import FormatError
from kinect_agent.formats import mocap_mapping
from kinect_agent.formats._rows import parse_floats
from kinect_agent.formats._text import read_lines
from kinect_agent.recording import Metadata, Recording

NAME = "bvh"
DESCRIPTION = "BVH optical motion capture (CMU naming mapped to the 20 joints)"
CMU_UNIT_M = 2.54 / 100 / 0.45  # metres per CMU ASF length unit
UNITS_M = {"CMU units": CMU_UNIT_M, "cm": 0.01, "inches": 0.0254, "m": 1.0, "mm": 0.001}
THIGH_RANGE_M = (0.3, 0.6)  # adults: the five units' ranges do not overlap
THIGH_RANGE_WIDE_M = (0.2, 0.7)  # children and tall adults, when no unit gives an adult thigh: one fit needed
_CHANNELS = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation")


@dataclass
class Joint:
    """One BVH joint or End Site: offset (3,) file units in the parent frame, channels in file order."""

    name: str
    parent: int
    offset: np.ndarray
    channels: list[str] = field(default_factory=list)
    first_channel: int = 0


def sniff(path: Path, head: bytes) -> bool:
    """True when the file starts with the HIERARCHY keyword."""
    return head.lstrip(b"\xef\xbb\xbf \t\r\n").startswith(b"HIERARCHY")


def read(path: Path) -> Recording:
    """Reads a BVH file into a 20-joint Recording (metres, y up); raises FormatError naming the line."""
    path = Path(path)
    lines = [(n, line.split()) for n, line in enumerate(read_lines(path), start=1)]
    lines = [(n, tok) for n, tok in lines if tok]
    joints, pos = parse_hierarchy(path, lines)
    rate_hz, motion = parse_motion(path, lines, pos, sum(len(j.channels) for j in joints))
    position_kind = position_channels(path, joints, motion)
    world = forward_kinematics(joints, motion)
    names = [j.name for j in joints]
    mapped = mocap_mapping.resolve(names)
    unit, scale = unit_scale(path, world, names, mapped)
    positions = np.full((motion.shape[0], skeleton.J, 3), np.nan)
    for ours, parts in mapped.items():
        positions[:, skeleton.INDEX[ours]] = np.mean([world[:, names.index(p)] for p in parts], axis=0) * scale
    meta = Metadata(device="mocap", rate_hz=rate_hz, source=str(path), subject=path.stem.split("_")[0])
    meta.extra.update(bvh_joints=len([j for j in joints if not j.name.endswith("_End")]), unit_m=scale, unit=unit)
    meta.extra["unmapped_joints"] = [j for j in skeleton.JOINTS if j not in mapped]
    if position_kind:
        meta.extra["position_channels"] = position_kind
    segments = path.with_name(f"{path.stem}_segments_from_mocap6.csv")
    if segments.is_file():
        with open(segments, encoding="utf-8", newline="") as f:
            meta.extra["segments"] = [dict(row) for row in csv.DictReader(f)]
    t = np.arange(motion.shape[0]) / rate_hz
    return Recording.from_positions(t, positions, meta)


def parse_hierarchy(path: Path, lines: list[tuple[int, list[str]]]) -> tuple[list[Joint], int]:
    """Returns the joints (parents before children; End Sites named `<parent>_End`) and the index of MOTION."""
    if not lines or lines[0][1][0] != "HIERARCHY":
        raise FormatError(path, "expected 'HIERARCHY' on the first line", lines[0][0] if lines else 1)
    joints: list[Joint] = []
    stack: list[int] = []
    n_channels = 0
    pending: Joint | None = None
    for pos in range(1, len(lines)):
        line_no, tok = lines[pos]
        key = tok[0]
        if key in ("ROOT", "JOINT") or (key == "End" and tok[1:2] == ["Site"]):
            if key != "ROOT" and not stack:
                raise FormatError(path, f"{key} outside any ROOT block", line_no)
            name = f"{joints[stack[-1]].name}_End" if key == "End" else " ".join(tok[1:]) or f"joint{len(joints)}"
            pending = Joint(name, stack[-1] if stack else -1, np.zeros(3))
        elif key == "{":
            if pending is None:
                raise FormatError(path, "'{' without a ROOT, JOINT or End Site before it", line_no)
            joints.append(pending)
            stack.append(len(joints) - 1)
            pending = None
        elif key == "}":
            if not stack:
                raise FormatError(path, "'}' without a matching '{'", line_no)
            stack.pop()
        elif key == "OFFSET":
            _need_open(path, stack, line_no, key)
            joints[stack[-1]].offset = parse_floats(path, line_no, tok[1:], 3, "OFFSET values")
        elif key == "CHANNELS":
            _need_open(path, stack, line_no, key)
            joints[stack[-1]].channels = _channels(path, line_no, tok)
            joints[stack[-1]].first_channel = n_channels
            n_channels += len(joints[stack[-1]].channels)
        elif key == "MOTION":
            if stack:
                raise FormatError(path, f"MOTION before {len(stack)} open block(s) were closed with '}}'", line_no)
            if not joints:
                raise FormatError(path, "no ROOT joint before MOTION", line_no)
            return joints, pos
        else:
            expected = "ROOT, JOINT, End Site, {, }, OFFSET, CHANNELS or MOTION"
            raise FormatError(path, f"unexpected {key!r} in HIERARCHY; expected {expected}", line_no)
    last = lines[-1][0] if lines else 1
    raise FormatError(path, "file ends without a MOTION section", last)


def parse_motion(path: Path, lines: list[tuple[int, list[str]]], pos: int, n_channels: int) -> tuple[float, np.ndarray]:
    """Returns (rate Hz, motion (T, C) float: channel values in file order, file units and degrees)."""
    header = lines[pos + 1 : pos + 3]
    frames_no = header[0][0] if header else lines[pos][0]
    if len(header) < 1 or header[0][1][:1] != ["Frames:"] or len(header[0][1]) != 2:
        raise FormatError(path, "expected 'Frames: <count>' after MOTION", frames_no)
    if len(header) < 2 or header[1][1][:2] != ["Frame", "Time:"] or len(header[1][1]) != 3:
        raise FormatError(path, "expected 'Frame Time: <seconds>' after 'Frames:'", frames_no + 1)
    n_frames = int(parse_floats(path, header[0][0], header[0][1][1:], 1, "frame count")[0])
    frame_time = float(parse_floats(path, header[1][0], header[1][1][2:], 1, "frame time")[0])
    if n_frames < 1 or frame_time <= 0:
        raise FormatError(path, f"need Frames >= 1 and Frame Time > 0, found {n_frames} and {frame_time}", frames_no)
    rows = lines[pos + 3 :]
    if len(rows) < n_frames:
        last = rows[-1][0] if rows else header[1][0]
        raise FormatError(path, f"file ends after {len(rows)} of {n_frames} frames (truncated?)", last)
    if len(rows) > n_frames:
        raise FormatError(path, f"more rows than 'Frames: {n_frames}' announces", rows[n_frames][0])
    motion = np.empty((n_frames, n_channels))
    for i, (line_no, tok) in enumerate(rows):
        if i == n_frames - 1 and len(tok) < n_channels:
            raise FormatError(path, f"expected {n_channels} channel values (frame {i}), found {len(tok)} (file "
                              "truncated?)", line_no)  # fmt: skip
        motion[i] = parse_floats(path, line_no, tok, n_channels, f"channel values (frame {i})")
    return 1.0 / frame_time, motion


def position_channels(path: Path, joints: list[Joint], motion: np.ndarray) -> dict[str, str]:
    """Makes the position channels of every joint a displacement from its OFFSET, in place in `motion`: values that
    follow the OFFSET (the joint's local position, as exporters writing positions on every joint do) have it
    subtracted. Returns {joint: "local position" | "displacement"} for joints whose OFFSET is not zero.

    motion: (T, C) channel values in file order, file units. Raises FormatError when the values are near neither."""
    kinds: dict[str, str] = {}
    for joint in joints:
        cols = [(joint.first_channel + c, "XYZ".index(n[0])) for c, n in enumerate(joint.channels) if "position" in n]
        size = float(np.linalg.norm(joint.offset))
        if not cols or size == 0.0:
            continue
        values = motion[:, [c for c, _ in cols]]
        offset = joint.offset[[a for _, a in cols]]
        to_offset = float(np.median(np.linalg.norm(values - offset, axis=-1)))
        to_zero = float(np.median(np.linalg.norm(values, axis=-1)))
        if min(to_offset, to_zero) > 0.5 * size and joint.parent >= 0:
            raise FormatError(path, f"position channels of joint {joint.name!r} are neither its OFFSET "
                              f"({size:.4g} file units) nor a displacement from it (median distance {to_offset:.4g} "
                              f"and {to_zero:.4g})")  # fmt: skip
        if to_offset < to_zero:
            motion[:, [c for c, _ in cols]] -= offset
            kinds[joint.name] = "local position"
        else:
            kinds[joint.name] = "displacement"
    return kinds


def forward_kinematics(joints: list[Joint], motion: np.ndarray) -> np.ndarray:
    """Returns world positions (T, N, 3) in file units (BVH world frame) of every joint and End Site.

    motion: (T, C) channel values in file order; positions in file units, rotations in degrees.
    """
    n_frames = motion.shape[0]
    world = np.zeros((n_frames, len(joints), 3))
    R_world = np.zeros((n_frames, len(joints), 3, 3))
    for k, joint in enumerate(joints):
        translation = np.broadcast_to(joint.offset, (n_frames, 3)).copy()
        R_parent_joint = np.broadcast_to(np.eye(3), (n_frames, 3, 3)).copy()
        for c, name in enumerate(joint.channels):
            values = motion[:, joint.first_channel + c]
            axis = "XYZ".index(name[0])
            if name.endswith("position"):
                translation[:, axis] += values
            else:
                R_parent_joint = R_parent_joint @ axis_rotation(axis, np.radians(values))
        if joint.parent < 0:
            world[:, k] = translation
            R_world[:, k] = R_parent_joint
        else:
            R_p = R_world[:, joint.parent]
            world[:, k] = world[:, joint.parent] + np.einsum("tij,tj->ti", R_p, translation)
            R_world[:, k] = R_p @ R_parent_joint
    return world


def unit_scale(
    path: Path, world: np.ndarray, names: list[str], mapped: dict[str, tuple[str, ...]]
) -> tuple[str, float]:
    """Returns (unit name, metres per file unit): the one unit of UNITS_M in which the first frame's thigh (left,
    else right: hip to knee) is 0.3-0.6 m, else 0.2-0.7 m. world: (T, N, 3) file units. Raises FormatError when there
    is no thigh, or no unit or two units fit."""
    for side in "LR":
        hip, knee = mapped.get(f"HIP_{side}"), mapped.get(f"KNE_{side}")
        if hip and knee:
            break
    else:
        shown = ", ".join(n for n in names if not n.endswith("_End"))
        raise FormatError(path, "cannot tell the length unit: no hip and knee joints found (expected names such as "
                          f"LeftUpLeg and LeftLeg, Left_Thigh and Left_Shin); joints in the file: {shown}")  # fmt: skip
    start = np.mean([world[0, names.index(p)] for p in hip], axis=0)
    end = np.mean([world[0, names.index(p)] for p in knee], axis=0)
    thigh = float(np.linalg.norm(end - start))
    tried = ", ".join(f"{thigh * scale:.3g} m in {unit}" for unit, scale in UNITS_M.items())
    for low, high in (THIGH_RANGE_M, THIGH_RANGE_WIDE_M):
        fits = [unit for unit, scale in UNITS_M.items() if low <= thigh * scale <= high]
        if len(fits) == 1:
            return fits[0], UNITS_M[fits[0]]
        if len(fits) > 1:
            raise FormatError(path, f"cannot tell the length unit: the thigh {hip[0]} -> {knee[0]} is {thigh:.4g} "
                              f"file units, {low}-{high} m in more than one unit ({tried})")  # fmt: skip
    raise FormatError(path, f"cannot tell the length unit: the thigh {hip[0]} -> {knee[0]} is {thigh:.4g} file units "
                      f"({tried}); expected 0.3-0.6 m (0.2-0.7 m) in one of them")  # fmt: skip


def _channels(path: Path, line_no: int, tok: list[str]) -> list[str]:
    count = int(parse_floats(path, line_no, tok[1:2], 1, "channel count")[0])
    names = tok[2:]
    if len(names) != count:
        raise FormatError(path, f"CHANNELS announces {count} channels but lists {len(names)}", line_no)
    for name in names:
        if name not in _CHANNELS:
            raise FormatError(path, f"unknown channel {name!r}; expected one of {', '.join(_CHANNELS)}", line_no)
    return names


def _need_open(path: Path, stack: list[int], line_no: int, key: str) -> None:
    if not stack:
        raise FormatError(path, f"{key} outside any joint block", line_no)
