"""One Kinect recording paired with simultaneous motion capture: read, aligned in time and space, or refused.

Scored joints (the ones aligned, registered and tabled) depend on what the mocap file's joints are:
    keraal_vicon   the SCoRE joint centres the reader fitted (not meta.extra["fallback_joints"]), plus ROOT when both
                   hips are and SPINE when ROOT and NECK are; HEAD, HAN_*, FOO_* are rigid-body targets, never scored.
    ui_prmd_vicon  UI_PRMD_JOINTS: the legs of the UI-PRMD Kinect files move with the pelvis (formats/ui_prmd.py)
                   and HEAD/HAN/FOO are marker clusters, not joint centres.
    other formats  every joint finite in at least half of the mocap frames.
Refusal (PairRefused, with every reason): speed correlation below MIN_XCORR, the speed-correlation lag and the
independent lowest-registration-RMS lag more than LAG_AGREE_FRAMES Kinect frames apart, registration RMS above
MAX_RMS_M, or fewer than MIN_FRAMES overlapping frames.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from kinect_agent import formats, skeleton
from kinect_agent.errors import AgentError, UnknownFormat
from kinect_agent.evaluation.align import MAX_LAG_S, Alignment, align, frame_rate
from kinect_agent.recording import Recording

SCORE_JOINTS = ("SHO_L", "ELB_L", "WRI_L", "SHO_R", "ELB_R", "WRI_R", "HIP_L", "KNE_L", "ANK_L",
                "HIP_R", "KNE_R", "ANK_R", "NECK")  # fmt: skip
UI_PRMD_JOINTS = ("ROOT", "SPINE", "NECK", "SHO_L", "ELB_L", "WRI_L", "SHO_R", "ELB_R", "WRI_R", "HIP_L", "HIP_R")
MIN_XCORR = 0.5  # the lag-agreement check is the stronger test; noisy Kinect speeds correlate at 0.6-0.9
LAG_AGREE_FRAMES = 2.0
MAX_RMS_M = 0.10
MAX_RMS_CALIBRATED_M = 0.30  # without registration the residual keeps the Kinect's mean joint offsets (up to 0.26 m)
MIN_FRAMES = 30
POSES = ("sitting", "standing")


class PairRefused(AgentError):
    """A Kinect/mocap pair that cannot be aligned; reasons: the failed checks, each one sentence."""

    def __init__(self, name: str, reasons: list[str]) -> None:
        super().__init__(f"{name}: refused: {'; '.join(reasons)}")
        self.name = name
        self.reasons = reasons


@dataclass(frozen=True)
class PairSpec:
    """What the user gave for one pair: the two files, their formats (None = detect), view (deg) and pose."""

    kinect: Path
    mocap: Path
    view_deg: float = 0.0
    pose: str = "standing"
    kinect_format: str | None = None
    mocap_format: str | None = None

    @property
    def name(self) -> str:
        """Returns a short name for reports: the Kinect file's name without its extensions."""
        return self.kinect.name.split(".")[0]


@dataclass(frozen=True)
class Pair:
    """An aligned pair. truth: (T, J, 3) m, mocap at the Kinect frames in the Kinect camera frame, NaN outside the
    overlap; joints: (J,) bool scored; overlap: (T,) bool frames where every scored joint has mocap."""

    spec: PairSpec
    kinect: Recording
    mocap: Recording
    joints: np.ndarray
    alignment: Alignment
    truth: np.ndarray
    overlap: np.ndarray


def well_estimated(fallback: list[str] | tuple[str, ...]) -> np.ndarray:
    """Returns (J,) bool: the KERAAL Vicon joints that are real joint-centre estimates (SCoRE fits kept, or derived)."""
    good = {j for j in SCORE_JOINTS if j not in fallback}
    if {"HIP_L", "HIP_R"} <= good:
        good.add("ROOT")
    if {"ROOT", "NECK"} <= good:
        good.add("SPINE")
    return np.array([j in good for j in skeleton.JOINTS])


def joint_mask(joints: tuple[str, ...]) -> np.ndarray:
    """Returns (J,) bool: True for the named joints."""
    return np.array([j in joints for j in skeleton.JOINTS])


def scored_joints(mocap_format: str, mocap: Recording) -> np.ndarray:
    """Returns (J,) bool: the joints compared (module docstring)."""
    if mocap_format == "keraal_vicon":
        return well_estimated(mocap.meta.extra.get("fallback_joints", []))
    if mocap_format == "ui_prmd_vicon":
        return joint_mask(UI_PRMD_JOINTS)
    return np.mean(np.all(np.isfinite(mocap.positions), axis=-1), axis=0) >= 0.5


def read(spec: PairSpec) -> tuple[Recording, Recording, str]:
    """Returns (Kinect recording, mocap recording, mocap format name); FormatError names the file and the problem."""
    kinect = formats.read(spec.kinect, spec.kinect_format)
    module = formats.get(spec.mocap_format) if spec.mocap_format else formats.detect(spec.mocap)
    mocap = formats.read(spec.mocap, module.NAME)
    return kinect, mocap, module.NAME


def refusals(al: Alignment, n_overlap: int, rate_hz: float, max_rms_m: float = MAX_RMS_M) -> list[str]:
    """Returns the reasons (possibly none) to refuse an alignment."""
    out = []
    if not np.isfinite(al.xcorr) or al.xcorr < MIN_XCORR:
        out.append(f"joint speeds correlate at r = {al.xcorr:.2f} at best (< {MIN_XCORR}): the motions do not match")
    if al.lag_rms_s is not None and abs(al.lag_rms_s - al.lag_s) * rate_hz > LAG_AGREE_FRAMES + 1e-6:
        out.append(f"lag estimates disagree: {al.lag_s:+.3f} s by speed correlation, {al.lag_rms_s:+.3f} s by "
                   f"registration (> {LAG_AGREE_FRAMES:g} frames apart)")  # fmt: skip
    if al.registration.rms_m > max_rms_m:
        out.append(f"registration residual {1e3 * al.registration.rms_m:.0f} mm RMS (> {1e3 * max_rms_m:.0f} mm)")
    if n_overlap < MIN_FRAMES:
        out.append(f"only {n_overlap} Kinect frames overlap the mocap (< {MIN_FRAMES})")
    return out


def make_pair(spec: PairSpec, max_lag_s: float = MAX_LAG_S, rigid: bool = True) -> Pair:
    """Reads, aligns and checks one pair; raises PairRefused (with the reasons) or FormatError.

    rigid=False: the mocap file is already in the Kinect camera frame (calibrated); no spatial registration.
    """
    if spec.pose not in POSES:
        raise ValueError(f"unknown pose {spec.pose!r}; use sitting or standing")
    kinect, mocap, mocap_format = read(spec)
    return align_pair(spec, kinect, mocap, scored_joints(mocap_format, mocap), max_lag_s, rigid)


def align_pair(spec: PairSpec, kinect: Recording, mocap: Recording, joints: np.ndarray,
               max_lag_s: float = MAX_LAG_S, rigid: bool = True) -> Pair:  # fmt: skip
    """Aligns recordings already read; joints (J,) bool scored. Raises PairRefused with the reasons."""
    if joints.sum() < 3:
        raise PairRefused(spec.name, [f"only {int(joints.sum())} joints have mocap (3 needed to register)"])
    if kinect.n_frames < MIN_FRAMES or mocap.n_frames < 2:
        raise PairRefused(spec.name, [f"too short: {kinect.n_frames} Kinect and {mocap.n_frames} mocap frames"])
    try:
        al = align(kinect, mocap, joints, max_lag_s=max_lag_s, rigid=rigid)
    except ValueError as exc:
        raise PairRefused(spec.name, [f"cannot register: {exc}"]) from None
    truth = al.truth(kinect, mocap)
    overlap = np.all(np.isfinite(truth[:, joints]), axis=(1, 2))
    reasons = refusals(al, int(overlap.sum()), frame_rate(kinect), MAX_RMS_M if rigid else MAX_RMS_CALIBRATED_M)
    if reasons:
        raise PairRefused(spec.name, reasons)
    return Pair(spec, kinect, mocap, joints, al, truth, overlap)


def _twin(path: Path) -> Path | None:
    """Returns the mocap file of a Kinect file by the naming rules of find_pairs, or None."""
    candidates = []
    if "Kinect" in path.name:
        candidates.append(path.with_name(path.name.replace("Kinect", "Vicon")))
    parts = path.parts
    if "Kinect" in parts:
        i = len(parts) - 1 - parts[::-1].index("Kinect")
        candidates.append(Path(*parts[:i], "Vicon", *parts[i + 1 :]))
    stem, _, rest = path.name.partition(".")
    if stem.endswith("_kinect"):
        candidates.append(path.with_name(f"{stem[: -len('kinect')]}mocap.{rest}"))
    return next((c for c in candidates if c.is_file() and c != path), None)


def _readable(path: Path) -> bool:
    """Returns True when some format recognises the file (folders also hold angle files, notes, ...)."""
    try:
        formats.detect(path)
    except UnknownFormat:
        return False
    return True


def find_pairs(folder: Path) -> list[tuple[Path, Path]]:
    """Returns the (Kinect, mocap) files under folder, sorted. A Kinect file is paired with: the same name with
    "Kinect" -> "Vicon" (KERAAL), the same path with a Kinect/ folder -> Vicon/ (UI-PRMD), or NAME_kinect.* with
    NAME_mocap.* with the same extension (any other format). Side files (*.meta.json) and files no format
    recognises are skipped."""
    if not folder.is_dir():
        raise FileNotFoundError(f"{folder}: not a folder")
    out = []
    for path in sorted(p for p in folder.rglob("*") if p.is_file() and not p.name.endswith(".meta.json")):
        if "Kinect" in path.name or "Kinect" in path.parts[len(folder.parts) :] or "_kinect." in path.name:
            twin = _twin(path)
            if twin is not None and _readable(path) and _readable(twin):
                out.append((path, twin))
    return out
