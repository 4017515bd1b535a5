"""Acclaim AMC motion files (HDM05, CMU) with their ASF skeleton, mapped onto the 20 joints.

AMC: optional `#` comments and `:FULLY-SPECIFIED` / `:DEGREES` / `:RADIANS` keywords, then frames: a line with the
frame number, followed by one line per bone with a dof: `<bone> <values in the ASF dof order>` (the root: the
ASF root order, e.g. TX TY TZ RX RY RZ). Angles may exceed ±360° (they are only fed to sin/cos).
The skeleton is found as: `<actor>.asf` or `HDM_<actor>.asf` beside the file or in an `asf/` folder beside it or
one level up (actor = the second `_` field of HDM_bd_squat..., else the first field: CMU `13_29.amc` -> 13.asf),
else the only .asf beside the file.
Forward kinematics in kinect_agent.formats.asf; joints via kinect_agent.formats.mocap_mapping; positions in metres
(ASF length unit, HDM05: 0.0254 / 0.45 m), in the mocap world frame (y up, not rotated into a camera frame).
Rate: the `_<Hz>` suffix of the file name (HDM05 `..._120.amc`), else 120 Hz with meta.extra["rate_assumed"].
The heading in frame 0 goes to meta.extra["facing_deg"] (0 = facing +z; the HDM05 clips face about -z, 180).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from kinect_agent import skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats import asf, mocap_mapping
from kinect_agent.formats._rows import is_number, number_hint
from kinect_agent.formats._text import last_content_line, read_lines
from kinect_agent.recording import Metadata, Recording

NAME = "amc"
DESCRIPTION = "Acclaim AMC motion + ASF skeleton (HDM05, CMU; asf/ folder or beside the .amc)"
DEFAULT_RATE_HZ = 120.0
THIGH_RANGE_M = (0.25, 0.7)  # hip to knee; outside it the ASF's `:units length` does not fit the bone lengths
_RATE_RE = re.compile(r"_(\d+)$")
_KEYWORDS = (b":FULLY-SPECIFIED", b":DEGREES", b":RADIANS")


def sniff(path: Path, head: bytes) -> bool:
    """True for a .amc file, or a text file whose header has the AMC keywords."""
    if path.is_dir() or b"\0" in head:
        return False
    if path.suffix.lower() == ".amc":
        return True
    stripped = [line.strip() for line in head.splitlines()[:20]]
    return any(line.upper() in _KEYWORDS for line in stripped)


def find_asf(path: Path) -> Path:
    """Returns the ASF skeleton of the AMC file at `path`; FormatError lists the places looked in."""
    parts = path.stem.split("_")
    actors = [parts[1]] if len(parts) > 2 and parts[0].upper() == "HDM" else []
    actors.append(parts[0])
    names = [n for a in actors for n in (f"{a}.asf", f"HDM_{a}.asf")]
    folders = [path.parent, path.parent / "asf", path.parent.parent / "asf", path.parent.parent]
    for folder in folders:
        for name in names:
            for candidate in (folder / name, folder / name.upper(), folder / name.replace(".asf", ".ASF")):
                if candidate.is_file():
                    return candidate
    beside = sorted(p for p in path.parent.iterdir() if p.suffix.lower() == ".asf")
    if len(beside) == 1:
        return beside[0]
    looked = ", ".join(str(f / n) for f in folders[:3] for n in names[:2])
    raise FormatError(path, f"no ASF skeleton found for this AMC file; looked for {looked}")


def read(path: Path, asf_path: Path | None = None) -> Recording:
    """Reads an AMC file (and its ASF) into a 20-joint Recording, metres, y up; FormatError names file and line."""
    path = Path(path)
    skel = asf.read(asf_path or find_asf(path))
    frame_numbers, root, dof_values, degrees = parse_motion(path, skel)
    world = asf.forward_kinematics(skel, root, dof_values, motion_degrees=degrees)
    names = list(world)
    scale = skel.metres_per_unit
    positions = np.full((root.shape[0], skeleton.J, 3), np.nan)
    for ours, parts in mocap_mapping.resolve(names).items():
        positions[:, skeleton.INDEX[ours]] = np.mean([world[p] for p in parts], axis=0) * scale
    _check_thigh(skel, positions[0])
    match = _RATE_RE.search(path.stem)
    rate = float(match.group(1)) if match and 0 < int(match.group(1)) <= 10000 else DEFAULT_RATE_HZ
    stem = path.stem.split("_")
    subject = stem[1] if len(stem) > 2 and stem[0].upper() == "HDM" else stem[0]
    meta = Metadata(device="mocap", rate_hz=rate, source=str(path), subject=subject)
    meta.extra.update(asf=str(skel.path), unit_m=scale, asf_bones=len(skel.bones), first_frame=int(frame_numbers[0]))
    meta.extra["facing_deg"] = facing_deg(positions[0])
    if match is None:
        meta.extra["rate_assumed"] = True
    if len(stem) >= 3 and stem[0].upper() == "HDM":
        meta.extra["motion_class"] = stem[2]
    t = (frame_numbers - frame_numbers[0]) / rate
    return Recording.from_positions(t, positions, meta)


def facing_deg(frame: np.ndarray) -> float:
    """Returns the subject's heading in one frame, degrees about +y from +z (90 = facing +x).

    frame: (J, 3) metres, y up. Facing = left × up, left = HIP_L - HIP_R (HDM05 clips mostly face -z: about 180).
    """
    left = frame[skeleton.INDEX["HIP_L"]] - frame[skeleton.INDEX["HIP_R"]]
    facing = np.cross(left, [0.0, 1.0, 0.0])
    return float(np.degrees(np.arctan2(facing[0], facing[2])))


def parse_motion(path: Path, skel: asf.Skeleton) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], bool | None]:
    """Returns (frame numbers (T,), root channels (T, len(root_order)), bone -> (T, n_dof) values, degrees flag).

    Every frame must give the root and every bone that has a dof, once each, with the ASF's number of values;
    frame numbers must increase. The degrees flag is True/False from :DEGREES/:RADIANS, None when absent.
    A file whose frames all list the bones in one order is read by a fast path; any other file, or one the fast
    path finds wrong, by the checked twin, which reads the same values or names the line of the error.
    """
    expected = {"root": len(skel.root_order)} | {b.name: len(b.dof) for b in skel.bones if b.dof}
    lines = read_lines(path)
    return parse_motion_fast(lines, expected) or parse_motion_checked(path, lines, expected)


def parse_motion_fast(
    lines: list[str], expected: dict[str, int]
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], bool | None] | None:
    """The fast path of parse_motion: None unless every frame lists each expected bone once, in the first frame's
    order, with the right number of finite values, and frame numbers increase."""
    frames: list[int] = []
    order: list[str] | None = None
    current: list[str] = []
    flat: list[str] = []
    degrees: bool | None = None
    for line in lines:
        tok = line.split()
        if not tok or tok[0][0] == "#":
            continue
        first = tok[0]
        if first[0] == ":":
            degrees = True if first.upper() == ":DEGREES" else False if first.upper() == ":RADIANS" else degrees
            continue
        if len(tok) == 1:
            if not first.isdigit() or (frames and current != order and order is not None):
                return None
            order = current if order is None and frames else order
            frames.append(int(first))
            current = []
            continue
        if not frames or expected.get(first, -1) != len(tok) - 1:
            return None
        current.append(first)
        flat.extend(tok[1:])
    if not frames or (order is not None and current != order):
        return None
    order = current if order is None else order
    if sorted(order) != sorted(expected) or len(set(order)) != len(order) or np.any(np.diff(frames) <= 0):
        return None
    try:
        values = np.array(flat, dtype=np.float64).reshape(len(frames), -1)
    except ValueError:
        return None
    if not np.all(np.isfinite(values)):
        return None
    columns, start = {}, 0
    for name in order:
        columns[name] = values[:, start : start + expected[name]]
        start += expected[name]
    root = columns.pop("root")
    return np.array(frames, dtype=np.float64), root, columns, degrees


def parse_motion_checked(
    path: Path, lines: list[str], expected: dict[str, int]
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], bool | None]:
    """The checked twin of parse_motion_fast: reads bones in any order per frame; FormatError names the line."""
    frames: list[int] = []
    values: dict[str, list[list[float]]] = {name: [] for name in expected}
    seen: set[str] = set()
    degrees: bool | None = None
    frame_line = 0
    last = last_content_line(lines) + 1  # its line number
    for line_no, line in enumerate(lines, start=1):
        tok = line.split()
        if not tok or tok[0].startswith("#"):
            continue
        if tok[0].startswith(":"):
            degrees = True if tok[0].upper() == ":DEGREES" else False if tok[0].upper() == ":RADIANS" else degrees
            continue
        if len(tok) == 1 and tok[0].isdigit():
            _check_complete(path, expected, seen, frames, frame_line)
            number = int(tok[0])
            if frames and number <= frames[-1]:
                raise FormatError(path, f"frame number {number} after {frames[-1]}: numbers must increase", line_no)
            frames.append(number)
            seen, frame_line = set(), line_no
            continue
        try:
            _bone_line(path, line_no, tok, expected, seen, values, bool(frames))
        except FormatError as exc:
            if line_no == last:
                raise FormatError(path, f"{exc.message} (file truncated?)", line_no) from None
            raise
    if not frames:
        raise FormatError(path, "no frames: expected a frame number line followed by bone lines")
    _check_complete(path, expected, seen, frames, frame_line, last=True)
    root = np.array(values.pop("root"), dtype=np.float64)
    return np.array(frames, dtype=np.float64), root, {k: np.array(v) for k, v in values.items()}, degrees


def _bone_line(
    path: Path,
    line_no: int,
    tok: list[str],
    expected: dict[str, int],
    seen: set[str],
    values: dict[str, Any],
    in_frame: bool,
) -> None:
    name = tok[0]
    if not in_frame:
        raise FormatError(path, f"bone line {name!r} before the first frame number", line_no)
    if name not in expected:
        known = "root and the ASF bones with a dof"
        raise FormatError(path, f"unknown bone {name!r}; expected {known} ({len(expected)} names)", line_no)
    if name in seen:
        raise FormatError(path, f"bone {name!r} given twice in one frame", line_no)
    if len(tok) - 1 != expected[name]:
        raise FormatError(path, f"bone {name!r}: expected {expected[name]} values, found {len(tok) - 1}", line_no)
    try:
        row = [float(c) for c in tok[1:]]
    except ValueError:
        hint = number_hint(next(c for c in tok[1:] if not is_number(c)))
        message = f"bone {name!r}: expected numbers, found {' '.join(tok[1:])!r}{hint}"
        raise FormatError(path, message, line_no) from None
    if not all(np.isfinite(row)):
        raise FormatError(path, f"bone {name!r}: values must be finite", line_no)
    seen.add(name)
    values[name].append(row)


def _check_complete(
    path: Path, expected: dict[str, int], seen: set[str], frames: list[int], frame_line: int, last: bool = False
) -> None:
    if not frames:
        return
    missing = [n for n in expected if n not in seen]
    if missing:
        hint = " (file truncated?)" if last else ""
        shown = ", ".join(missing[:5]) + (" ..." if len(missing) > 5 else "")
        raise FormatError(path, f"frame {frames[-1]} lacks bone(s) {shown}{hint}", frame_line)


def _check_thigh(skel: asf.Skeleton, frame: np.ndarray) -> None:
    """Refuses a skeleton whose thigh (hip to knee, first frame) is not 0.25-0.7 m: its `:units length` does not
    give metres. A skeleton without hip and knee keeps its declared unit unchecked. frame: (20, 3) metres."""
    thighs = [frame[skeleton.INDEX[f"KNE_{s}"]] - frame[skeleton.INDEX[f"HIP_{s}"]] for s in "LR"]
    lengths = [float(np.linalg.norm(d)) for d in thighs if np.all(np.isfinite(d))]
    if not lengths:
        return
    thigh = max(lengths)
    if not THIGH_RANGE_M[0] <= thigh <= THIGH_RANGE_M[1]:
        raise FormatError(skel.path, f"the thigh is {thigh:.3g} m with ':units length {skel.length_unit:g}' (metres = "
                          f"file units x 0.0254 / {skel.length_unit:g}); expected {THIGH_RANGE_M[0]}-"
                          f"{THIGH_RANGE_M[1]} m: check the :units length line")  # fmt: skip
