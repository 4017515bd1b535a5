"""KERAAL Vicon/ART rigid-body files (Devanne, Nguyen et al.; readme_files_format.txt section 1).

One frame per line: 17 ART rigid-body targets, each x y z (millimetres, lab frame, z up) then the target's global
orientation quaternion qx qy qz qw (scalar last; rotates target-frame vectors into the lab frame): 119 numbers.
Targets (TARGETS below) sit on the segments, not at joint centres, so the joints are estimated:
    SCoRE (Ehrig et al. 2006, J Biomech 39:2798) between adjacent rigid bodies A, B: the centre c_A (A's frame)
    and c_B (B's frame) minimising sum_t ||R_A(t) c_A + p_A(t) - R_B(t) c_B - p_B(t)||^2, one linear least
    squares over all frames; the joint is the mean of its two world-frame images.
        SHO_* Shoulder target - Arm (lower residual than Chest - Arm in 5 of the 6 arm fits measured);
        ELB_* Arm - Forearm;  WRI_* Forearm - Hand;  HIP_* Hips - Thigh;  KNE_* Thigh - Tibia;
        ANK_* Tibia - Foot;  NECK Chest - Head.
    A fit is kept only when the motion excites the joint (condition number of the system <= MAX_CONDITION, i.e.
    enough relative rotation) and the two bodies do share a fixed centre (RMS residual <= MAX_RMS_MM; skin or
    scapula sliding breaks this for the shoulder during overhead reaching). Otherwise the joint falls back to a
    fixed estimate (as do both hips when their SCoRE centres are not 120-300 mm apart, HIP_WIDTH_MM): SHO_* the
    Shoulder target itself (on the acromion), any other joint the midpoint of its two
    targets. meta.extra["fallback_joints"] lists them; meta.extra["score"] gives each fit's numbers.
    HEAD Head target;  HAN_* Hand target;  FOO_* Foot target;  ROOT midpoint of HIP_L and HIP_R (the pelvis
    centre, as Kinect's SpineBase, rather than the Hips target on the sacrum);  SPINE midpoint of ROOT and NECK.
A target whose seven values contain a NaN, or whose position is 0 0 0, is missing in that frame: joints that need
it are NaN (state 0). A SCoRE joint with one of its two targets present uses that target's image of the centre.
Frame: the lab has the subject facing +x with their left at +y, z up; this module returns metres, y up, subject
facing -z with their left at -x (as a Kinect facing them sees it): (x, y, z) -> (-y, z, -x) / 1000.
Rate: 60 Hz assumed (not in the files; each Vicon file has 1.98-2.02 times the rows of its paired Kinect file,
which is read at 30 Hz), meta.extra["rate_assumed"] = True.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from kinect_agent import skeleton
from kinect_agent.formats import kinect_joints
from kinect_agent.recording import Metadata, Recording

NAME = "keraal_vicon"
DESCRIPTION = "KERAAL Vicon/ART text (17 rigid bodies x y z qx qy qz qw per line, mm, 60 Hz assumed)"
RATE_HZ = 60.0
TARGETS: tuple[str, ...] = (
    "R_FOREARM", "L_FOREARM", "R_ARM", "L_ARM", "CHEST", "R_THIGH", "L_THIGH", "R_SHOULDER", "L_SHOULDER",
    "R_HAND", "L_HAND", "R_FOOT", "L_FOOT", "HIPS", "HEAD", "R_TIBIA", "L_TIBIA",
)  # fmt: skip
FIELDS_PER_TARGET = 7
N_FIELDS = len(TARGETS) * FIELDS_PER_TARGET
MAX_CONDITION = 75.0  # above: too little relative rotation (knees, ankles of a seated subject: 80-330)
HIP_WIDTH_MM = (120.0, 300.0)  # plausible distance between the hip centres; outside it both hips fall back
MAX_RMS_MM = 18.0  # above: no fixed common centre (well-fitted elbows, wrists: 1.6-4.4 mm; shoulders 9-15 mm)
_T = {name: i for i, name in enumerate(TARGETS)}
# Our joint -> (proximal target, distal target) of its SCoRE fit.
SCORE_PAIRS: dict[str, tuple[str, str]] = {
    "SHO_L": ("L_SHOULDER", "L_ARM"), "ELB_L": ("L_ARM", "L_FOREARM"), "WRI_L": ("L_FOREARM", "L_HAND"),
    "SHO_R": ("R_SHOULDER", "R_ARM"), "ELB_R": ("R_ARM", "R_FOREARM"), "WRI_R": ("R_FOREARM", "R_HAND"),
    "HIP_L": ("HIPS", "L_THIGH"), "KNE_L": ("L_THIGH", "L_TIBIA"), "ANK_L": ("L_TIBIA", "L_FOOT"),
    "HIP_R": ("HIPS", "R_THIGH"), "KNE_R": ("R_THIGH", "R_TIBIA"), "ANK_R": ("R_TIBIA", "R_FOOT"),
    "NECK": ("CHEST", "HEAD"),
}  # fmt: skip
TARGET_JOINTS: dict[str, str] = {
    "HEAD": "HEAD", "HAN_L": "L_HAND", "HAN_R": "R_HAND", "FOO_L": "L_FOOT", "FOO_R": "R_FOOT",
}  # fmt: skip
_LAB_TO_OURS = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])  # rows: our x, y, z in lab axes


def sniff(path: Path, head: bytes) -> bool:
    """True when the first line holds 119 numbers whose 17 quaternions are unit (or missing)."""
    cells = kinect_joints.first_line_fields(head)
    if cells is None or len(cells) != N_FIELDS:
        return False
    quats = np.array(cells, dtype=np.float64).reshape(len(TARGETS), FIELDS_PER_TARGET)[:, 3:]
    present = np.all(np.isfinite(quats), axis=-1) & np.any(quats != 0.0, axis=-1)
    return bool(present.any()) and bool(np.all(np.abs(np.linalg.norm(quats[present], axis=-1) - 1.0) < 1e-3))


def read(path: Path) -> Recording:
    """Reads a KERAAL Vicon file into a 20-joint mocap recording (m, y up, 60 Hz assumed); FormatError on bad rows."""
    path = Path(path)
    values, _, _ = kinect_joints.read_numeric_rows(path, N_FIELDS)
    p_lab_target, R_lab_target = split_targets(values)
    joints_mm, fits = joints_from_targets(p_lab_target, R_lab_target)
    positions = joints_mm @ _LAB_TO_OURS.T / 1000.0
    meta = Metadata(device="mocap", rate_hz=RATE_HZ, source=str(path))
    meta.extra.update(dataset="KERAAL Vicon", rate_assumed=True, score=fits)
    meta.extra["fallback_joints"] = sorted(j for j, fit in fits.items() if not fit["used"])
    meta.extra["missing_targets"] = {
        TARGETS[k]: int(n) for k, n in enumerate(np.isnan(p_lab_target[..., 0]).sum(axis=0)) if n
    }
    parts = path.stem.split("-")
    if len(parts) >= 4 and parts[1].lower() == "vicon":
        meta.exercise, meta.subject, meta.extra["group"] = parts[2], parts[3], parts[0]
        meta.extra["recording"] = path.stem
    meta.history.append("keraal_vicon: joint centres by SCoRE from rigid bodies")
    t = np.arange(len(positions)) / RATE_HZ
    return Recording.from_positions(t, positions, meta)


def split_targets(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Splits rows (T, 119) into target positions (T, 17, 3) mm lab frame and rotations R_lab_target (T, 17, 3, 3).

    A target with a NaN among its 7 values or a 0 0 0 position is missing: NaN position and rotation."""
    targets = values.reshape(len(values), len(TARGETS), FIELDS_PER_TARGET)
    p = targets[..., :3].copy()
    q = targets[..., 3:]
    norm = np.linalg.norm(q, axis=-1)
    missing = ~np.all(np.isfinite(targets), axis=-1) | np.all(p == 0.0, axis=-1) | ~(norm > 0.5)
    p[missing] = np.nan
    with np.errstate(invalid="ignore", divide="ignore"):
        R = quat_xyzw_to_matrix(q / norm[..., None])
    R[missing] = np.nan
    return p, R


def quat_xyzw_to_matrix(q: np.ndarray) -> np.ndarray:
    """Returns rotation matrices (..., 3, 3) from unit quaternions (..., 4) stored scalar last (x y z w)."""
    x, y, z, w = np.moveaxis(q, -1, 0)
    rows = (
        1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
        2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
        2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y),
    )  # fmt: skip
    return np.stack(rows, axis=-1).reshape(q.shape[:-1] + (3, 3))


def score_fit(
    p_a: np.ndarray, R_a: np.ndarray, p_b: np.ndarray, R_b: np.ndarray
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Fits one joint centre by SCoRE (Ehrig et al. 2006) over the frames where both bodies are present.

    p_a, p_b: (T, 3) float, mm, lab frame, NaN = missing; R_a, R_b: (T, 3, 3) R_lab_body, NaN = missing.
    returns: c_a (3,) mm in A's frame, c_b (3,) mm in B's frame, the condition number of the (3N, 6) system and
    the RMS distance (mm) between the two world images of the centre; NaN centres when no frame has both bodies.
    """
    both = np.all(np.isfinite(p_a), axis=-1) & np.all(np.isfinite(p_b), axis=-1)
    if both.sum() < 2:
        return np.full(3, np.nan), np.full(3, np.nan), float("inf"), float("nan")
    A = np.concatenate([R_a[both], -R_b[both]], axis=-1).reshape(-1, 6)  # (3N, 6)
    y = (p_b[both] - p_a[both]).reshape(-1)  # (3N,) mm
    c, _, _, s = np.linalg.lstsq(A, y, rcond=None)
    residual = (A @ c - y).reshape(-1, 3)
    rms = float(np.sqrt(np.mean(np.sum(residual**2, axis=-1))))
    return c[:3], c[3:], float(s[0] / s[-1]) if s[-1] > 0 else float("inf"), rms


def score_centre(
    p_a: np.ndarray, R_a: np.ndarray, c_a: np.ndarray, p_b: np.ndarray, R_b: np.ndarray, c_b: np.ndarray
) -> np.ndarray:
    """Returns the joint (T, 3) mm lab frame: the mean of R_a c_a + p_a and R_b c_b + p_b, or the one present."""
    images = np.stack([R_a @ c_a + p_a, R_b @ c_b + p_b])  # (2, T, 3)
    count = np.sum(np.isfinite(images[..., 0]), axis=0)[:, None]
    with np.errstate(invalid="ignore"):
        return np.where(count > 0, np.nansum(images, axis=0) / count, np.nan)


def joints_from_targets(p: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, dict[str, dict[str, Any]]]:
    """Estimates the 20 joints from the 17 rigid bodies.

    p: (T, 17, 3) float, mm, lab frame, NaN = missing; R: (T, 17, 3, 3) R_lab_target, NaN = missing.
    returns: joints (T, 20, 3) float, mm, lab frame, NaN = not estimable; and per SCoRE joint its fit numbers
    (condition, rms_mm, used: whether SCoRE was kept rather than the fallback).
    """
    out = np.full(p.shape[:1] + (skeleton.J, 3), np.nan)
    fits: dict[str, dict[str, Any]] = {}
    for joint, (a, b) in SCORE_PAIRS.items():
        ia, ib = _T[a], _T[b]
        c_a, c_b, cond, rms = score_fit(p[:, ia], R[:, ia], p[:, ib], R[:, ib])
        used = bool(cond <= MAX_CONDITION and rms <= MAX_RMS_MM)
        fits[joint] = {"pair": [a, b], "condition": round(cond, 1), "rms_mm": round(rms, 2), "used": used}
        if used:
            out[:, skeleton.INDEX[joint]] = score_centre(p[:, ia], R[:, ia], c_a, p[:, ib], R[:, ib], c_b)
        else:
            out[:, skeleton.INDEX[joint]] = p[:, ia] if joint.startswith("SHO") else 0.5 * (p[:, ia] + p[:, ib])
    _check_hip_width(out, p, fits)
    for joint, target in TARGET_JOINTS.items():
        out[:, skeleton.INDEX[joint]] = p[:, _T[target]]
    ix = skeleton.INDEX
    out[:, ix["ROOT"]] = 0.5 * (out[:, ix["HIP_L"]] + out[:, ix["HIP_R"]])
    out[:, ix["SPINE"]] = 0.5 * (out[:, ix["ROOT"]] + out[:, ix["NECK"]])
    return out, fits


def _check_hip_width(out: np.ndarray, p: np.ndarray, fits: dict[str, dict[str, Any]]) -> None:
    """Replaces both SCoRE hips by the fallback when their median distance is outside HIP_WIDTH_MM.

    out: (T, 20, 3) mm lab frame, updated in place; p: (T, 17, 3) target positions, mm, lab frame.
    A seated subject's pelvis tilts about the common hip axis, which leaves the centres free along it."""
    if not (fits["HIP_L"]["used"] and fits["HIP_R"]["used"]):
        return
    width = float(
        np.nanmedian(np.linalg.norm(out[:, skeleton.INDEX["HIP_L"]] - out[:, skeleton.INDEX["HIP_R"]], axis=-1))
    )
    if HIP_WIDTH_MM[0] <= width <= HIP_WIDTH_MM[1]:
        return
    for joint in ("HIP_L", "HIP_R"):
        a, b = SCORE_PAIRS[joint]
        out[:, skeleton.INDEX[joint]] = 0.5 * (p[:, _T[a]] + p[:, _T[b]])
        fits[joint].update(used=False, hip_width_mm=round(width, 1))
