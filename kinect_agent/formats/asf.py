"""Acclaim ASF skeleton files (the skeleton half of ASF/AMC motion capture: CMU, HDM05).

Parsed sections: `:units` (length, angle), `:root` (order, axis, position, orientation), `:bonedata`
(id, name, direction, length, axis <ax ay az> <ORDER>, dof) and `:hierarchy`. Other sections are skipped.

Conventions (Acclaim spec, as in the CMU and HDM05 tools):
    C = axis rotation of a bone, composed in its ORDER (XYZ: C = Rz(az) Ry(ay) Rx(ax), rotations about fixed
    axes applied first-listed first); M = the AMC rotation composed the same way in dof order.
    R_world_bone = R_world_parent · C · M · C⁻¹;  end_bone = start_bone + length · R_world_bone · direction.
    The root bone's start is the AMC root translation, its R_world = C_root · M_root · C_root⁻¹.
Units: lengths in file units; metres = units × (0.0254 / `:units length`) (HDM05 and CMU: length 0.45, i.e.
0.05644 m per unit, lengths stored as inches × 0.45); angles in degrees unless `:units angle rad`, which holds for
the ASF's own angles (bone axes, root orientation) and for the AMC values unless the AMC says :DEGREES / :RADIANS.
Plain or gzip, any line ends, BOM, Latin-1 comments (formats._text).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from kinect_agent.body.rotations import euler
from kinect_agent.errors import FormatError
from kinect_agent.formats._rows import parse_floats
from kinect_agent.formats._text import read_lines

INCH_M = 0.0254
_AXES = "XYZ"


@dataclass
class Bone:
    """One ASF bone: direction (3,) unit, parent frame at rest; length in file units; axis (3,) angles in the ASF's
    angle unit, composed in axis_order; dof like ["rx", "rz"]."""

    name: str
    direction: np.ndarray
    length: float
    axis: np.ndarray
    axis_order: str
    dof: list[str] = field(default_factory=list)
    parent: int = -1  # index into Skeleton.bones; -1 = the root


@dataclass
class Skeleton:
    """A parsed ASF file. bones are ordered parents first; root_order like ["TX", ..., "RZ"]."""

    path: Path
    length_unit: float = 1.0  # the `:units length` value
    degrees: bool = True
    root_order: list[str] = field(default_factory=lambda: ["TX", "TY", "TZ", "RX", "RY", "RZ"])
    root_axis_order: str = "XYZ"
    root_position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    root_orientation: np.ndarray = field(default_factory=lambda: np.zeros(3))
    bones: list[Bone] = field(default_factory=list)

    @property
    def metres_per_unit(self) -> float:
        """Metres per ASF length unit (Acclaim: file lengths are inches times `:units length`)."""
        return INCH_M / self.length_unit

    def index(self, name: str) -> int:
        """Returns the index of the bone called `name`."""
        return [b.name for b in self.bones].index(name)


def read(path: str | Path) -> Skeleton:
    """Parses an ASF file; raises FormatError naming the file, line and what was expected."""
    path = Path(path)
    lines = [(n, line.split()) for n, line in enumerate(read_lines(path), start=1)]
    lines = [(n, tok) for n, tok in lines if tok and not tok[0].startswith("#")]
    skel = Skeleton(path)
    bones: dict[str, Bone] = {}
    children: list[tuple[int, str, list[str]]] = []
    section, current, current_line = "", None, 0
    for line_no, tok in lines:
        if tok[0].startswith(":"):
            section = tok[0].lower()
            continue
        if section == ":units":
            _units(skel, path, line_no, tok)
        elif section == ":root":
            _root(skel, path, line_no, tok)
        elif section == ":bonedata":
            if tok[0] == "begin":
                current, current_line = Bone("", np.zeros(3), 0.0, np.zeros(3), "XYZ"), line_no
            elif tok[0] == "end":
                if current is None or not current.name:
                    raise FormatError(path, "bone block without a 'name' line", current_line or line_no)
                bones[current.name] = current
                current = None
            elif current is not None:
                _bone_field(current, path, line_no, tok)
        elif section == ":hierarchy" and tok[0] not in ("begin", "end"):
            children.append((line_no, tok[0], tok[1:]))
    if current is not None:
        raise FormatError(path, "file ends inside a bone block (missing 'end')", current_line)
    if not bones:
        raise FormatError(path, "no :bonedata bones found; expected an Acclaim ASF skeleton")
    skel.bones = _order(path, bones, children)
    return skel


def _units(skel: Skeleton, path: Path, line_no: int, tok: list[str]) -> None:
    if tok[0] == "length":
        skel.length_unit = parse_floats(path, line_no, tok[1:], 1, "length unit")[0]
        if skel.length_unit <= 0:
            raise FormatError(path, f"length unit must be positive, found {skel.length_unit}", line_no)
    elif tok[0] == "angle":
        if tok[1:2] not in (["deg"], ["rad"]):
            raise FormatError(path, f"expected 'angle deg' or 'angle rad', found {' '.join(tok)!r}", line_no)
        skel.degrees = tok[1] == "deg"


def _root(skel: Skeleton, path: Path, line_no: int, tok: list[str]) -> None:
    key = tok[0].lower()
    if key == "order":
        order = [t.upper() for t in tok[1:]]
        bad = [t for t in order if t not in ("TX", "TY", "TZ", "RX", "RY", "RZ")]
        if bad or not order:
            raise FormatError(path, f"root order: expected TX TY TZ RX RY RZ in some order, found {tok[1:]}", line_no)
        skel.root_order = order
    elif key == "axis":
        skel.root_axis_order = _order_token(path, line_no, tok[1:2])
    elif key == "position":
        skel.root_position = parse_floats(path, line_no, tok[1:], 3, "root position values")
    elif key == "orientation":
        skel.root_orientation = parse_floats(path, line_no, tok[1:], 3, "root orientation values")


def _bone_field(bone: Bone, path: Path, line_no: int, tok: list[str]) -> None:
    key = tok[0].lower()
    if key == "name":
        bone.name = tok[1] if len(tok) > 1 else ""
    elif key == "direction":
        bone.direction = parse_floats(path, line_no, tok[1:], 3, "direction values")
        norm = float(np.linalg.norm(bone.direction))
        bone.direction = bone.direction / norm if norm > 0 else bone.direction
    elif key == "length":
        bone.length = parse_floats(path, line_no, tok[1:], 1, "bone length")[0]
    elif key == "axis":
        bone.axis = parse_floats(path, line_no, tok[1:4], 3, "axis angles")
        bone.axis_order = _order_token(path, line_no, tok[4:5])
    elif key == "dof":
        dof = [t.lower() for t in tok[1:]]
        bad = [t for t in dof if t not in ("rx", "ry", "rz", "tx", "ty", "tz", "l")]
        if bad:
            raise FormatError(path, f"unknown dof {bad[0]!r}; expected rx, ry, rz (tx, ty, tz, l)", line_no)
        bone.dof = dof


def _order_token(path: Path, line_no: int, tok: list[str]) -> str:
    order = tok[0].upper() if tok else ""
    if sorted(order) != ["X", "Y", "Z"]:
        raise FormatError(path, f"expected an axis order such as XYZ, found {order or 'nothing'!r}", line_no)
    return order


def _order(path: Path, bones: dict[str, Bone], children: list[tuple[int, str, list[str]]]) -> list[Bone]:
    """Returns the bones parents first, with parent indices set from the :hierarchy lines."""
    parent_of: dict[str, str] = {}
    for line_no, parent, kids in children:
        if parent != "root" and parent not in bones:
            raise FormatError(path, f"hierarchy names unknown bone {parent!r}", line_no)
        for kid in kids:
            if kid not in bones:
                raise FormatError(path, f"hierarchy names unknown bone {kid!r}", line_no)
            parent_of[kid] = parent
    ordered: list[Bone] = []
    frontier = ["root"]
    while frontier:
        name = frontier.pop(0)
        for kid in [k for k, p in parent_of.items() if p == name]:
            bone = bones[kid]
            bone.parent = -1 if name == "root" else [b.name for b in ordered].index(name)
            ordered.append(bone)
            frontier.append(kid)
    missing = [n for n in bones if n not in {b.name for b in ordered}]
    if missing:
        raise FormatError(path, f"bones not reachable from root in :hierarchy: {', '.join(missing)}")
    return ordered


def forward_kinematics(
    skel: Skeleton, root: np.ndarray, dof_values: dict[str, np.ndarray], motion_degrees: bool | None = None
) -> dict[str, np.ndarray]:
    """Returns the world position of every bone's start and end, file units, ASF world frame.

    root: (T, 6) float, the root channels in skel.root_order (file units; angles in degrees or radians per
    motion_degrees, or skel.degrees when it is None). dof_values: bone name -> (T, len(bone.dof)) float in the bone's
    dof order, same angle unit; bones without dof may be absent. The ASF's own angles follow skel.degrees.
    returns: {"root": (T, 3), "<bone>": (T, 3) start of the bone, "<bone>_End": (T, 3) end of the bone}.
    """
    T = root.shape[0]
    to_rad = np.pi / 180.0 if (skel.degrees if motion_degrees is None else motion_degrees) else 1.0
    asf_to_rad = np.pi / 180.0 if skel.degrees else 1.0
    translation = np.broadcast_to(skel.root_position, (T, 3)).copy()
    rot = np.zeros((T, 3))
    for k, channel in enumerate(skel.root_order):
        target = translation if channel[0] == "T" else rot
        target[:, _AXES.index(channel[1])] = root[:, k] * (1.0 if channel[0] == "T" else to_rad)
    rot_order = "".join(c[1] for c in skel.root_order if c[0] == "R") or "XYZ"
    rot = rot[:, [_AXES.index(a) for a in rot_order]]
    C_root = euler((skel.root_orientation * asf_to_rad)[[_AXES.index(a) for a in skel.root_axis_order]],
                   skel.root_axis_order)  # fmt: skip
    R_root = C_root @ euler(rot, rot_order) @ C_root.T
    out = {"root": translation}
    R_world: list[np.ndarray] = []
    ends: list[np.ndarray] = []
    for bone in skel.bones:
        R_parent = R_root if bone.parent < 0 else R_world[bone.parent]
        start = translation if bone.parent < 0 else ends[bone.parent]
        C = euler((bone.axis * asf_to_rad)[[_AXES.index(a) for a in bone.axis_order]], bone.axis_order)
        M = _motion_rotation(bone, dof_values.get(bone.name), T, to_rad)
        R = R_parent @ (C @ M @ C.T)
        end = start + bone.length * (R @ bone.direction)
        R_world.append(R)
        ends.append(end)
        out[bone.name] = start
        out[f"{bone.name}_End"] = end
    return out


def _motion_rotation(bone: Bone, values: np.ndarray | None, T: int, to_rad: float) -> np.ndarray:
    """Returns (T, 3, 3): the bone's AMC rotation, its rotational dofs composed in listed order."""
    rotational = [(k, d) for k, d in enumerate(bone.dof) if d.startswith("r")]
    if values is None or not rotational:
        return np.broadcast_to(np.eye(3), (T, 3, 3))
    angles = np.stack([values[:, k] for k, _ in rotational], axis=-1) * to_rad
    return euler(angles, "".join(d[1] for _, d in rotational))
