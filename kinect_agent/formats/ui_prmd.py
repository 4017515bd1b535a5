"""UI-PRMD Kinect recordings (Vakanski et al. 2018, https://webpages.uidaho.edu/ui-prmd/).

Each episode is two headerless CSV files (optionally gzipped), 66 columns = 22 joints x 3, ~30 Hz:
    .../Kinect/Positions/mXX_sYY_eZZ_positions.txt   joint 0 absolute, the others offsets from the parent, cm
    .../Kinect/Angles/mXX_sYY_eZZ_angles.txt         per joint Euler angles (x, y, z columns), degrees
Incorrectly performed episodes are named ..._positions_inc.txt / ..._angles_inc.txt (meta.extra["incorrect"]).
Absolute positions are rebuilt as in the dataset's visualisation code (python port:
tejas1904/UI-PRMD-Visualize-python-port, visualize.py): position = parent position + R @ offset, where R
chains the rotations R(angles) = Rz(a_z) Ry(a_y) Rx(a_x) of the joints above. As in that code, the collars
use the chest rotation alone (not chained through the spine) and the hips the waist rotation alone.

Dataset frame: x to the subject's left, y up, z forward from the subject (towards the camera), cm. This
module returns the Kinect camera frame (x to the subject's right, y up, z away from the camera, metres),
i.e. a 180 degree turn about y: (x, y, z) -> (-x, y, -z).

The Vicon files (117 columns = 39 joints) have another layout and are not read here.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body.rotations import euler
from kinect_agent.errors import FormatError
from kinect_agent.formats._rows import read_csv_table
from kinect_agent.recording import Metadata, Recording

NAME = "ui_prmd"
DESCRIPTION = "UI-PRMD Kinect episode (mXX_sYY_eZZ_positions.txt[.gz] + sibling Angles folder)"
RATE_HZ = 30.0
N_SOURCE_JOINTS = 22
N_COLUMNS = 3 * N_SOURCE_JOINTS
CM_TO_M = 0.01

# "_inc" marks the incorrectly performed episodes ("Incorrect Segmented Movements").
_NAME_RE = re.compile(r"^(m\d\d)_(s\d\d)_(e\d\d)_positions(_inc)?\.txt(\.gz)?$")

# The 22 joints of the files, in column order.
SOURCE_JOINTS: tuple[str, ...] = (
    "Waist", "Spine", "Chest", "Neck", "Head", "Head tip",
    "Left collar", "Left upper arm", "Left forearm", "Left hand",
    "Right collar", "Right upper arm", "Right forearm", "Right hand",
    "Left upper leg", "Left lower leg", "Left foot", "Left leg toes",
    "Right upper leg", "Right lower leg", "Right foot", "Right leg toes",
)  # fmt: skip
# SOURCE_PARENT[j]: the joint whose position the offset of j starts from (-1 for the waist).
SOURCE_PARENT = np.array([-1, 0, 1, 2, 3, 4, 2, 6, 7, 8, 2, 10, 11, 12, 0, 14, 15, 16, 0, 18, 19, 20])
# ROTATION_BASE[j]: the joint whose accumulated rotation is multiplied by R(angles[SOURCE_PARENT[j]]);
# -1 = start from the identity (collars and hips, as in the reference code).
ROTATION_BASE = np.array([-1, -1, 1, 2, 3, 4, -1, 6, 7, 8, -1, 10, 11, 12, -1, 14, 15, 16, -1, 18, 19, 20])

# Our joint -> source joint. The chest is where the collars attach: Kinect's shoulder centre.
# The files have no hand tip, so HAN_* copy the wrist ("Left hand") and are marked inferred.
MAPPING: dict[str, str] = {
    "ROOT": "Waist", "SPINE": "Spine", "NECK": "Chest", "HEAD": "Head",
    "SHO_L": "Left upper arm", "ELB_L": "Left forearm", "WRI_L": "Left hand", "HAN_L": "Left hand",
    "SHO_R": "Right upper arm", "ELB_R": "Right forearm", "WRI_R": "Right hand", "HAN_R": "Right hand",
    "HIP_L": "Left upper leg", "KNE_L": "Left lower leg", "ANK_L": "Left foot", "FOO_L": "Left leg toes",
    "HIP_R": "Right upper leg", "KNE_R": "Right lower leg", "ANK_R": "Right foot", "FOO_R": "Right leg toes",
}  # fmt: skip
_SOURCE_OF = np.array([SOURCE_JOINTS.index(MAPPING[name]) for name in skeleton.JOINTS])
_COPIED = [skeleton.INDEX["HAN_L"], skeleton.INDEX["HAN_R"]]
_DATASET_TO_CAMERA = np.array([-1.0, 1.0, -1.0])


def sniff(path: Path, head: bytes) -> bool:
    """True for a file named mXX_sYY_eZZ_positions.txt[.gz] or a folder holding such files."""
    if path.is_dir():
        return bool(_positions_files(path))
    return bool(_NAME_RE.match(path.name))


def read(path: Path) -> Recording:
    """Reads one episode (a positions file) or all episodes of the one movement and subject in a folder."""
    path = Path(path)
    if path.is_dir():
        return _read_folder(path)
    return read_episode(path)


def read_episode(positions_path: Path) -> Recording:
    """Reads one episode; the angles file is found in the sibling Angles folder.

    returns: a Recording at 30 Hz, positions (T, 20, 3) m, Kinect camera frame (y up), HAN_* inferred.
    """
    positions_path = Path(positions_path)
    match = _NAME_RE.match(positions_path.name)
    if not match:
        raise FormatError(positions_path, "expected a file named mXX_sYY_eZZ_positions.txt or .txt.gz")
    movement, subject, episode, incorrect, _ = match.groups()
    angles_path = _angles_path(positions_path)
    offsets_cm = _read_table(positions_path)
    angles_deg = _read_table(angles_path)
    if len(offsets_cm) != len(angles_deg):
        raise FormatError(
            angles_path, f"has {len(angles_deg)} frames but {positions_path.name} has {len(offsets_cm)}; expected equal"
        )
    joints_m = forward_kinematics(offsets_cm, angles_deg) * CM_TO_M * _DATASET_TO_CAMERA
    positions = joints_m[:, _SOURCE_OF]
    t = np.arange(len(positions)) / RATE_HZ
    meta = Metadata(
        device="kinect2",
        rate_hz=RATE_HZ,
        subject=subject,
        exercise=movement,
        source=str(positions_path),
        extra={
            "episode": episode,
            "incorrect": bool(incorrect),
            "dataset": "UI-PRMD",
            "angles_file": str(angles_path),
        },
    )
    rec = Recording.from_positions(t, positions, meta)
    rec.state[:, _COPIED] = np.where(
        rec.state[:, _COPIED] == skeleton.TRACKED, skeleton.INFERRED, rec.state[:, _COPIED]
    )
    return rec


def read_episodes(folder: Path, *, movement: str, subject: str) -> Recording:
    """Reads every episode of one movement ("m01") and subject ("s01") in `folder`, joined in episode order.

    folder: a Positions folder, or a folder with a Positions (or Kinect/Positions) subfolder.
    returns: one Recording; meta.extra["part_start_s"] gives each episode's start time (s).
    """
    folder = Path(folder)
    files = [p for p in _positions_files(folder) if _key(p)[:2] == (movement, subject)]
    if not files:
        raise FormatError(folder, f"no {movement}_{subject}_eZZ_positions.txt[.gz] files found")
    parts = [read_episode(p) for p in sorted(files, key=_key)]
    rec = Recording.concatenate(parts)
    rec.meta.extra["episode"] = [p.meta.extra["episode"] for p in parts]
    rec.meta.source = str(folder)
    return rec


def forward_kinematics(offsets_cm: np.ndarray, angles_deg: np.ndarray) -> np.ndarray:
    """Rebuilds absolute joint positions from UI-PRMD offsets and Euler angles.

    offsets_cm: (T, 22, 3) float, cm, dataset frame; row 0 absolute, others offsets from SOURCE_PARENT.
    angles_deg: (T, 22, 3) float, degrees, per joint (x, y, z) angles; R = Rz Ry Rx.
    returns: (T, 22, 3) float, cm, dataset frame, absolute positions.
    """
    local = euler(np.deg2rad(angles_deg), "XYZ")  # (T, 22, 3, 3) = Rz @ Ry @ Rx
    n = offsets_cm.shape[0]
    rotation = np.empty_like(local)  # rotation applied to each joint's offset
    absolute = np.empty_like(offsets_cm)
    absolute[:, 0] = offsets_cm[:, 0]
    for j in range(1, N_SOURCE_JOINTS):
        parent, base = SOURCE_PARENT[j], ROTATION_BASE[j]
        base_rotation = rotation[:, base] if base >= 0 else np.broadcast_to(np.eye(3), (n, 3, 3))
        rotation[:, j] = base_rotation @ local[:, parent]
        absolute[:, j] = absolute[:, parent] + np.einsum("tij,tj->ti", rotation[:, j], offsets_cm[:, j])
    return absolute


def _read_table(path: Path) -> np.ndarray:
    """Reads a headerless 66-column CSV (gz or plain); returns (T, 22, 3) float."""
    if not path.is_file():
        raise FormatError(path, "missing file: expected it beside the positions file's folder")
    rows = read_csv_table(path, N_COLUMNS, "22 joints x 3")
    return rows.reshape(len(rows), N_SOURCE_JOINTS, 3)


def _angles_path(positions_path: Path) -> Path:
    """The angles file of a positions file: ../Angles/mXX_sYY_eZZ_angles[_inc].txt[.gz], same compression first."""
    folder = positions_path.parent.parent / "Angles"
    stem = positions_path.name.replace("_positions", "_angles")
    candidates = [folder / stem, folder / (stem[:-3] if stem.endswith(".gz") else stem + ".gz")]
    return next((c for c in candidates if c.is_file()), candidates[0])


def _positions_files(folder: Path) -> list[Path]:
    """Positions files in `folder`, its Positions subfolder or its Kinect/Positions subfolder."""
    for candidate in (folder, folder / "Positions", folder / "Kinect" / "Positions"):
        if candidate.is_dir():
            files = [p for p in candidate.iterdir() if _NAME_RE.match(p.name)]
            if files:
                return files
    return []


def _key(path: Path) -> tuple[str, str, str]:
    movement, subject, episode, _, _ = _NAME_RE.match(path.name).groups()
    return movement, subject, episode


def _read_folder(folder: Path) -> Recording:
    files = _positions_files(folder)
    if not files:
        raise FormatError(folder, "no mXX_sYY_eZZ_positions.txt[.gz] files in this folder")
    groups = sorted({_key(p)[:2] for p in files})
    if len(groups) > 1:
        shown = ", ".join(f"{m}_{s}" for m, s in groups[:5]) + (" ..." if len(groups) > 5 else "")
        raise FormatError(
            folder,
            f"holds {len(groups)} movement/subject pairs ({shown}); expected one: give a narrower folder "
            "or use ui_prmd.read_episodes(folder, movement='m01', subject='s01')",
        )
    movement, subject = groups[0]
    return read_episodes(folder, movement=movement, subject=subject)
