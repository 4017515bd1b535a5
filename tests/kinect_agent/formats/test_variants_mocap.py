"""Motion-capture readers on files from other sources than our samples: BVH with Mixamo, `Left_Thigh`-style and
`Thigh_L` names, XYZ channel order, position channels on every joint, a long Frame Time, lengths in cm, inches,
metres or mm (the unit guess checked on each, an impossible one refused); ASF with `:units angle rad` or another
`:units length`; AMC with angles beyond 360°, radians, bones in another order per frame, repeated frames, NaN.

Each variant is built in tmp_path from short cuts of the real CMU 13_29 BVH and HDM05 squat, and must give the clean
file's joints to 1e-9 m, or be refused naming the file and line.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from kinect_agent import cli, formats, skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats import amc, asf, bvh

from .test_variants import build_amc, build_bvh


@pytest.fixture
def cmu(data_dir: Path, tmp_path: Path) -> tuple[Path, list[bvh.Joint], np.ndarray]:
    """A 30-frame cut of CMU 13_29: (path, joints, motion (30, C))."""
    path = build_bvh(data_dir, tmp_path)
    lines = [(n, line.split()) for n, line in enumerate(path.read_text().splitlines(), start=1)]
    lines = [(n, tok) for n, tok in lines if tok]
    joints, pos = bvh.parse_hierarchy(path, lines)
    _, motion = bvh.parse_motion(path, lines, pos, sum(len(j.channels) for j in joints))
    return path, joints, motion


def _write_bvh(path: Path, joints: list[bvh.Joint], motion: np.ndarray, frame_time: str = ".0083333") -> None:
    """Writes joints (names, offsets, channels as given) and motion (T, C) as a BVH file."""
    out = ["HIERARCHY"]
    children = {k: [c for c, j in enumerate(joints) if j.parent == k] for k in range(-1, len(joints))}

    def block(k: int, depth: int) -> None:
        joint, pad = joints[k], "  " * depth
        if joint.name.endswith("_End") and not joint.channels and not children[k]:
            out.append(f"{pad}End Site")
        else:
            out.append(f"{pad}{'ROOT' if joint.parent < 0 else 'JOINT'} {joint.name}")
        out.append(pad + "{")
        out.append(f"{pad}  OFFSET {' '.join(f'{v:.9g}' for v in joint.offset)}")
        if joint.channels:
            out.append(f"{pad}  CHANNELS {len(joint.channels)} {' '.join(joint.channels)}")
        for child in children[k]:
            block(child, depth + 1)
        out.append(pad + "}")

    block(0, 0)
    out += ["MOTION", f"Frames: {len(motion)}", f"Frame Time: {frame_time}"]
    out += [" ".join(f"{v:.10g}" for v in row) for row in motion]
    path.write_text("\n".join(out) + "\n")


def _renamed(joints: list[bvh.Joint], rename) -> list[bvh.Joint]:
    """Copies joints with each non-End name passed through rename (End Sites follow their parent)."""
    out = []
    for j in joints:
        name = j.name if j.name.endswith("_End") else rename(j.name)
        out.append(bvh.Joint(name, j.parent, j.offset.copy(), list(j.channels), j.first_channel))
    for j in out:
        if j.name.endswith("_End"):
            j.name = out[j.parent].name + "_End"
    return out


def _same(path: Path, clean, what: str, atol: float = 1e-9) -> None:
    rec = formats.read(path)
    assert rec.n_frames == clean.n_frames, what
    np.testing.assert_allclose(rec.positions, clean.positions, atol=atol, err_msg=what)


def _side_suffix(name: str) -> str:
    """LeftUpLeg -> Thigh_L style."""
    words = {"UpLeg": "Thigh", "Leg": "Shin", "Foot": "Foot", "ToeBase": "Toe", "Arm": "UpperArm", "ForeArm": "Forearm",
             "Hand": "Hand", "HandIndex1": "Index1", "Shoulder": "Clavicle", "HandThumb1": "Thumb1",
             "FingerBase": "Palm"}  # fmt: skip
    for side, letter in (("Left", "L"), ("Right", "R")):
        if name.startswith(side) and name[len(side) :] in words:
            return f"{words[name[len(side) :]]}_{letter}"
    return {"Hips": "Pelvis", "LHipJoint": "HipRoot_L", "RHipJoint": "HipRoot_R"}.get(name, name)


def _side_prefix(name: str) -> str:
    """LeftUpLeg -> Left_Thigh style."""
    renamed = _side_suffix(name)
    if renamed.endswith(("_L", "_R")):
        return ("Left_" if renamed.endswith("_L") else "Right_") + renamed[:-2]
    return renamed


@pytest.mark.parametrize(
    "rename",
    [lambda n: f"mixamorig:{n}", _side_suffix, _side_prefix, lambda n: _side_prefix(n).lower()],
    ids=["mixamorig_prefix", "Thigh_L", "Left_Thigh", "left_thigh"],
)
def test_bvh_joint_names_of_other_sources(cmu, tmp_path: Path, rename) -> None:
    path, joints, motion = cmu
    clean = formats.read(path)
    out = tmp_path / "named.bvh"
    _write_bvh(out, _renamed(joints, rename), motion)
    _same(out, clean, "renamed")
    assert formats.read(out).meta.extra["unmapped_joints"] == []


def test_bvh_xyz_channel_order(cmu, tmp_path: Path) -> None:
    path, joints, motion = cmu
    clean = formats.read(path)
    moved = motion.copy()
    new = _renamed(joints, lambda n: n)
    for joint in new:
        rot = [c for c, n in enumerate(joint.channels) if n.endswith("rotation")]
        if not rot:
            continue
        order = "".join(joint.channels[c][0] for c in rot)
        cols = [joint.first_channel + c for c in rot]
        matrices = Rotation.from_euler(order.upper(), motion[:, cols], degrees=True)
        moved[:, cols] = matrices.as_euler("XYZ", degrees=True)
        for c, axis in zip(rot, "XYZ", strict=True):
            joint.channels[c] = f"{axis}rotation"
    out = tmp_path / "xyz.bvh"
    _write_bvh(out, new, moved)
    assert "CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation" in out.read_text()
    _same(out, clean, "XYZ order", atol=1e-7)


def _with_positions_everywhere(joints: list[bvh.Joint], motion: np.ndarray, values) -> tuple[list[Any], np.ndarray]:
    """Gives every joint with rotations three position channels first, filled with values(joint) (3,)."""
    new, columns, first = [], [], 0
    for joint in joints:
        channels = list(joint.channels)
        cols = [motion[:, joint.first_channel + c] for c in range(len(channels))]
        if channels and not any("position" in c for c in channels):
            channels = ["Xposition", "Yposition", "Zposition"] + channels
            cols = [np.full(len(motion), v) for v in values(joint)] + cols
        new.append(bvh.Joint(joint.name, joint.parent, joint.offset.copy(), channels, first))
        columns += cols
        first += len(channels)
    return new, np.stack(columns, axis=1)


@pytest.mark.parametrize(
    ("kind", "values"), [("local position", lambda j: j.offset), ("displacement", lambda j: 0 * j.offset)]
)
def test_bvh_position_channels_on_every_joint(cmu, tmp_path: Path, kind: str, values) -> None:
    path, joints, motion = cmu
    clean = formats.read(path)
    new, moved = _with_positions_everywhere(joints, motion, values)
    out = tmp_path / "positions.bvh"
    _write_bvh(out, new, moved)
    _same(out, clean, kind)
    assert formats.read(out).meta.extra["position_channels"]["LeftLeg"] == kind


def test_bvh_position_channels_near_neither_offset_nor_zero_are_refused(cmu, tmp_path: Path) -> None:
    _, joints, motion = cmu
    new, moved = _with_positions_everywhere(joints, motion, lambda j: 3 * j.offset)
    out = tmp_path / "positions.bvh"
    _write_bvh(out, new, moved)
    with pytest.raises(FormatError, match=r"positions\.bvh: position channels of joint '\w+' are neither its OFFSET"):
        formats.read(out)


def test_bvh_frame_time_with_many_digits(cmu, tmp_path: Path) -> None:
    path, joints, motion = cmu
    out = tmp_path / "long_time.bvh"
    _write_bvh(out, joints, motion, frame_time="0.008333333333333333")
    rec = formats.read(out)
    assert rec.rate_hz == pytest.approx(120.0, rel=1e-12)
    np.testing.assert_allclose(rec.t, np.arange(30) / 120.0, atol=1e-12)


def _scaled(joints, motion: np.ndarray, k: float):
    """Returns (joints, motion) with every length (offsets and position channels) multiplied by k."""
    scaled, moved = _renamed(joints, lambda n: n), motion.copy()
    for joint in scaled:
        joint.offset = joint.offset * k
        for c, name in enumerate(joint.channels):
            if name.endswith("position"):
                moved[:, joint.first_channel + c] *= k
    return scaled, moved


@pytest.mark.parametrize("unit", ["cm", "inches", "m", "mm"])
def test_bvh_length_unit_is_found_on_each_kind(cmu, tmp_path: Path, unit: str) -> None:
    path, joints, motion = cmu
    clean = formats.read(path)
    k = bvh.CMU_UNIT_M / bvh.UNITS_M[unit]
    scaled, moved = _scaled(joints, motion, k)
    out = tmp_path / f"{unit}.bvh"
    _write_bvh(out, scaled, moved)
    rec = formats.read(out)
    assert rec.meta.extra["unit"] == unit and rec.meta.extra["unit_m"] == bvh.UNITS_M[unit]
    np.testing.assert_allclose(rec.positions, clean.positions, atol=1e-8)


@pytest.mark.parametrize("k", [0.25, 13.5])  # thighs of 1.9 and 100 file units: 0.2-0.7 m in no unit
def test_bvh_length_unit_that_no_thigh_fits_is_refused(cmu, tmp_path: Path, k: float) -> None:
    _, joints, motion = cmu
    scaled = _renamed(joints, lambda n: n)
    for joint in scaled:
        joint.offset = joint.offset * k
    out = tmp_path / "odd.bvh"
    _write_bvh(out, scaled, motion)
    with pytest.raises(FormatError, match=r"odd\.bvh: cannot tell the length unit: the thigh LeftUpLeg -> LeftLeg"):
        formats.read(out)


@pytest.mark.parametrize(("unit", "thigh_m", "found"), [("m", 0.25, True), ("mm", 0.65, True), ("cm", 0.25, False)])
def test_bvh_child_or_tall_thigh_unit_found_when_only_one_fits(cmu, tmp_path, unit: str, thigh_m: float, found) -> None:
    path, joints, motion = cmu
    clean = formats.read(path)
    hip, knee = (clean.positions[0, skeleton.INDEX[j]] for j in ("HIP_L", "KNE_L"))
    k = thigh_m / float(np.linalg.norm(knee - hip)) * bvh.CMU_UNIT_M / bvh.UNITS_M[unit]
    scaled, moved = _scaled(joints, motion, k)
    out = tmp_path / f"{unit}.bvh"
    _write_bvh(out, scaled, moved)
    if not found:  # 25 cm is a child's thigh in cm or an adult's (0.64 m) in inches
        with pytest.raises(FormatError, match=r"cm\.bvh: cannot tell the length unit: .* in more than one unit"):
            formats.read(out)
        return
    rec = formats.read(out)
    assert rec.meta.extra["unit"] == unit
    scale = thigh_m / float(np.linalg.norm(knee - hip))
    np.testing.assert_allclose(rec.positions, clean.positions * scale, atol=1e-8)


def test_bvh_with_unknown_joint_names_is_refused_listing_them(cmu, tmp_path: Path) -> None:
    _, joints, motion = cmu
    out = tmp_path / "anon.bvh"
    _write_bvh(out, _renamed(joints, lambda n: f"bone{abs(hash(n)) % 997}"), motion)
    with pytest.raises(FormatError, match=r"anon\.bvh: cannot tell the length unit: no hip and knee joints.*bone"):
        formats.read(out)


def test_bvh_nan_in_motion_is_refused_with_its_line(cmu, tmp_path: Path) -> None:
    path, _, _ = cmu
    lines = path.read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("Frame Time")) + 5
    lines[k] = " ".join(["nan"] + lines[k].split()[1:])
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(FormatError) as info:
        formats.read(path)
    assert info.value.line == k + 1 and "finite" in info.value.message


# --- ASF / AMC ---------------------------------------------------------------------------------------------------


@pytest.fixture
def squat(data_dir: Path, tmp_path: Path) -> tuple[Path, Path]:
    """A 20-frame cut of an HDM05 squat and its ASF: (amc path, asf path)."""
    return build_amc(data_dir, tmp_path), tmp_path / "asf" / "HDM_bd.asf"


def _edit_asf(path: Path, edit_line) -> None:
    lines = path.read_bytes().decode("latin-1").splitlines()
    path.write_bytes("\n".join(edit_line(line) for line in lines).encode("latin-1"))


def _edit_amc_values(path: Path, skel: asf.Skeleton, edit, drop_keywords: bool = False) -> None:
    """Applies edit(value, is_rotation) to every AMC value."""
    dofs = {"root": [c.lower() for c in skel.root_order]} | {b.name: b.dof for b in skel.bones}
    out = []
    for line in path.read_bytes().decode("latin-1").splitlines():
        tok = line.split()
        if drop_keywords and line.strip() in (":DEGREES", ":RADIANS"):
            continue
        if len(tok) > 1 and tok[0] in dofs:
            values = [edit(float(v), d.startswith("r")) for v, d in zip(tok[1:], dofs[tok[0]], strict=True)]
            line = " ".join([tok[0]] + [f"{v:.17g}" for v in values])
        out.append(line)
    path.write_bytes("\n".join(out).encode("latin-1") + b"\n")


def test_asf_angle_rad_holds_for_axes_and_root_orientation(squat) -> None:
    path, asf_path = squat
    clean = amc.read(path)

    def to_rad(line: str) -> str:
        tok = line.split()
        if tok[:2] == ["angle", "deg"]:
            return "  angle rad"
        if tok and tok[0] in ("axis", "orientation") and len(tok) >= 4:
            return " ".join([tok[0]] + [f"{np.radians(float(v)):.17g}" for v in tok[1:4]] + tok[4:])
        return line

    _edit_asf(asf_path, to_rad)
    _same(path, clean, "ASF in radians, AMC :DEGREES")
    _edit_amc_values(path, asf.read(asf_path), lambda v, rot: np.radians(v) if rot else v, drop_keywords=True)
    _same(path, clean, "ASF in radians, AMC in the ASF's unit")


def test_amc_radians_keyword(squat) -> None:
    path, asf_path = squat
    clean = amc.read(path)
    _edit_amc_values(path, asf.read(asf_path), lambda v, rot: np.radians(v) if rot else v)
    path.write_bytes(path.read_bytes().replace(b":DEGREES", b":RADIANS"))
    _same(path, clean, ":RADIANS")


def test_asf_length_unit_one_is_inches(squat) -> None:
    path, asf_path = squat
    clean = amc.read(path)
    k = 1 / 0.45

    def to_inches(line: str) -> str:
        tok = line.split()
        if tok[:1] == ["length"]:
            return f"  length {float(tok[1]) * k!r}" if tok[1] != "0.45" else "  length 1"
        if tok[:1] == ["position"]:
            return " ".join(["position"] + [repr(float(v) * k) for v in tok[1:]])
        return line

    _edit_asf(asf_path, to_inches)
    _edit_amc_values(path, asf.read(asf_path), lambda v, rot: v if rot else v * k)
    _same(path, clean, "length 1")


def test_asf_length_unit_that_does_not_fit_its_lengths_is_refused(squat) -> None:
    path, asf_path = squat
    _edit_asf(asf_path, lambda line: "  length 0.045" if line.split() == ["length", "0.45"] else line)
    with pytest.raises(FormatError, match=r"HDM_bd\.asf: the thigh is .* m with ':units length 0.045'"):
        amc.read(path)
    out = path.parent / "o.csv"
    assert cli.main(["convert", str(path), "-o", str(out)]) == 2 and not out.exists()


@pytest.mark.parametrize("turns", [1, -2, 5])
def test_amc_angles_beyond_360(squat, turns: int) -> None:
    path, asf_path = squat
    clean = amc.read(path)
    _edit_amc_values(path, asf.read(asf_path), lambda v, rot: v + 360.0 * turns if rot else v)
    _same(path, clean, f"{turns} turns", atol=1e-9)


def test_amc_bones_in_another_order_per_frame_read_by_the_checked_path(squat) -> None:
    path, asf_path = squat
    clean = amc.read(path)
    skel = asf.read(asf_path)
    lines = path.read_bytes().decode("latin-1").splitlines()
    frames, head, current = [], [], None
    for line in lines:
        if line.strip().isdigit():
            current = [line]
            frames.append(current)
        elif current is None:
            head.append(line)
        else:
            current.append(line)
    for k, frame in enumerate(frames):  # each frame its own order
        frame[1:] = frame[1:][k % 3 :] + frame[1:][: k % 3]
    path.write_bytes("\n".join(head + [line for f in frames for line in f]).encode("latin-1") + b"\n")
    assert amc.parse_motion_fast(path.read_text(encoding="latin-1").splitlines(), {"root": 6} | {
        b.name: len(b.dof) for b in skel.bones if b.dof}) is None  # fmt: skip
    rec = amc.read(path)
    np.testing.assert_array_equal(rec.positions, clean.positions)


def test_amc_fast_path_and_checked_twin_agree(squat) -> None:
    path, asf_path = squat
    skel = asf.read(asf_path)
    expected = {"root": len(skel.root_order)} | {b.name: len(b.dof) for b in skel.bones if b.dof}
    lines = path.read_text(encoding="latin-1").splitlines()
    fast, checked = amc.parse_motion_fast(lines, expected), amc.parse_motion_checked(path, lines, expected)
    assert fast is not None
    np.testing.assert_array_equal(fast[0], checked[0])
    np.testing.assert_array_equal(fast[1], checked[1])
    assert fast[2].keys() == checked[2].keys() and fast[3] == checked[3]
    for name in fast[2]:
        np.testing.assert_array_equal(fast[2][name], checked[2][name], err_msg=name)


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (lambda lines, k: lines[:k] + ["5"] + lines[k + 1 :], "frame number 5 after 5"),
        (lambda lines, k: lines[: k + 1] + [re.sub(r" \S+", " nan", lines[k + 1], count=1)] + lines[k + 2 :], "finite"),
    ],
    ids=["repeated_frame_number", "nan_value"],
)
def test_amc_repeated_frame_and_nan_are_refused_with_the_line(squat, edit, words: str) -> None:
    path, _ = squat
    lines = path.read_bytes().decode("latin-1").splitlines()
    k = next(i for i, line in enumerate(lines) if line.strip() == "6")
    bad = edit(lines, k)
    path.write_bytes("\n".join(bad).encode("latin-1") + b"\n")
    with pytest.raises(FormatError) as info:
        amc.read(path)
    assert info.value.path == str(path) and info.value.line in (k + 1, k + 2) and words in info.value.message, str(
        info.value
    )
    assert re.search(words, str(info.value))
