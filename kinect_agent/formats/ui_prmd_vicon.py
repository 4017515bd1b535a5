"""UI-PRMD Vicon recordings (Vakanski et al. 2018): .../Vicon/Positions/mXX_sYY_eZZ_positions[_inc].txt[.gz].

Headerless CSV, 117 columns = 39 points x (x y z), millimetres, z up. The column order is not written in the data
folder; the heights and left/right pairs match the 39 markers of Vicon's Plug-in Gait full-body model in its
standard order (MARKERS below: 4 head, C7, T10, CLAV, STRN, RBAK, 7 per arm, 4 pelvis, 6 per leg), which
tests/kinect_agent/formats/test_ui_prmd_vicon.py checks on every file (head highest, toes lowest, the moving arm of
shoulder abduction, left markers on the subject's left). Markers sit on the skin, so the joints are estimates:
    ROOT  mean of the 4 pelvis markers;  HIP_*  Bell et al. (1990) hip centre from the ASIS/PSIS markers
          (19 % of the inter-ASIS width posterior, 30 % inferior, 36 % lateral of mid-ASIS);
    SPINE mid(T10, STRN);  NECK mid(C7, CLAV);  HEAD mean of the 4 head markers;
    SHO_* xSHO (acromion);  ELB_* xELB;  WRI_* mid(xWRA, xWRB);  HAN_* xFIN;  KNE_* xKNE;  ANK_* xANK;  FOO_* xTOE.
A marker written as 0,0,0 is missing: joints use the markers present, and are not tracked when none is.
Frame: the lab frame has the subject facing +x with their left at +y; this module returns metres, y up, subject
facing -z with their left at -x (as a Kinect facing them sees it): (x, y, z) -> (-y, z, -x) / 1000.
Rate: 100 Hz (the UI-PRMD paper's Vicon rate; not in the files), meta.extra["rate_assumed"] = True.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np

from kinect_agent import skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats._rows import read_csv_table
from kinect_agent.recording import Metadata, Recording

NAME = "ui_prmd_vicon"
DESCRIPTION = "UI-PRMD Vicon episode (Vicon/Positions/mXX_sYY_eZZ_positions.txt[.gz], 39 markers, mm)"
RATE_HZ = 100.0
MARKERS: tuple[str, ...] = (
    "LFHD", "RFHD", "LBHD", "RBHD", "C7", "T10", "CLAV", "STRN", "RBAK",
    "LSHO", "LUPA", "LELB", "LFRM", "LWRA", "LWRB", "LFIN",
    "RSHO", "RUPA", "RELB", "RFRM", "RWRA", "RWRB", "RFIN",
    "LASI", "RASI", "LPSI", "RPSI",
    "LTHI", "LKNE", "LTIB", "LANK", "LHEE", "LTOE",
    "RTHI", "RKNE", "RTIB", "RANK", "RHEE", "RTOE",
)  # fmt: skip
N_COLUMNS = 3 * len(MARKERS)
_NAME_RE = re.compile(r"^(m\d\d)_(s\d\d)_(e\d\d)_positions(_inc)?\.txt(\.gz)?$")
_M = {name: i for i, name in enumerate(MARKERS)}
# Our joint -> markers whose mean gives it (the hips are computed apart).
_MEAN_OF: dict[str, tuple[str, ...]] = {
    "ROOT": ("LASI", "RASI", "LPSI", "RPSI"), "SPINE": ("T10", "STRN"), "NECK": ("C7", "CLAV"),
    "HEAD": ("LFHD", "RFHD", "LBHD", "RBHD"),
    "SHO_L": ("LSHO",), "ELB_L": ("LELB",), "WRI_L": ("LWRA", "LWRB"), "HAN_L": ("LFIN",),
    "SHO_R": ("RSHO",), "ELB_R": ("RELB",), "WRI_R": ("RWRA", "RWRB"), "HAN_R": ("RFIN",),
    "KNE_L": ("LKNE",), "ANK_L": ("LANK",), "FOO_L": ("LTOE",),
    "KNE_R": ("RKNE",), "ANK_R": ("RANK",), "FOO_R": ("RTOE",),
}  # fmt: skip
_LAB_TO_OURS = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])  # rows: our x, y, z in lab axes


def sniff(path: Path, head: bytes) -> bool:
    """True for a UI-PRMD positions file (by name) whose first row has 117 columns (Kinect files have 66)."""
    if path.is_dir() or not _NAME_RE.match(path.name):
        return False
    first = next((line for line in head.decode("utf-8", "replace").splitlines() if line.strip()), "")
    return len(first.split(",")) == N_COLUMNS


def read(path: Path) -> Recording:
    """Reads one Vicon episode into a 20-joint Recording (metres, y up, facing -z); FormatError names file and line."""
    path = Path(path)
    match = _NAME_RE.match(path.name)
    if not match:
        raise FormatError(path, "expected a file named mXX_sYY_eZZ_positions[_inc].txt[.gz]")
    lab_mm = read_markers(path)
    missing = np.all(lab_mm == 0.0, axis=-1)  # (T, 39): the files write a lost marker as 0,0,0
    lab_mm[missing] = np.nan
    lab = joints_from_markers(lab_mm)
    positions = lab @ _LAB_TO_OURS.T / 1000.0
    movement, subject, episode, incorrect, _ = match.groups()
    meta = Metadata(device="mocap", rate_hz=RATE_HZ, subject=subject, exercise=movement, source=str(path))
    meta.extra.update(episode=episode, incorrect=bool(incorrect), dataset="UI-PRMD Vicon", rate_assumed=True)
    meta.extra["missing_markers"] = {MARKERS[m]: int(n) for m, n in enumerate(missing.sum(axis=0)) if n}
    t = np.arange(len(positions)) / RATE_HZ
    return Recording.from_positions(t, positions, meta)


def read_markers(path: Path) -> np.ndarray:
    """Returns the markers (T, 39, 3), millimetres, lab frame (z up); FormatError on a bad row."""
    rows = read_csv_table(path, N_COLUMNS, "39 markers x 3")
    return rows.reshape(len(rows), len(MARKERS), 3)


def joints_from_markers(markers: np.ndarray) -> np.ndarray:
    """Returns the 20 joints (T, 20, 3) from Plug-in Gait markers (T, 39, 3), same unit and frame, NaN = missing.

    A joint made of several markers uses those present; the hips need all four pelvis markers."""
    out = np.empty(markers.shape[:1] + (skeleton.J, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all markers of a joint missing -> NaN, as wanted
        for joint, names in _MEAN_OF.items():
            out[:, skeleton.INDEX[joint]] = np.nanmean(markers[:, [_M[n] for n in names]], axis=1)
    out[:, skeleton.INDEX["HIP_L"]], out[:, skeleton.INDEX["HIP_R"]] = hip_centres(markers)
    return out


def hip_centres(markers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Returns (left, right) hip joint centres (T, 3) by Bell et al. (1990) from the ASIS/PSIS markers."""
    lasi, rasi = markers[:, _M["LASI"]], markers[:, _M["RASI"]]
    psis = 0.5 * (markers[:, _M["LPSI"]] + markers[:, _M["RPSI"]])
    origin = 0.5 * (lasi + rasi)
    width = np.linalg.norm(lasi - rasi, axis=-1, keepdims=True)
    lateral = (lasi - rasi) / width
    back = psis - origin
    back -= np.sum(back * lateral, axis=-1, keepdims=True) * lateral
    back /= np.linalg.norm(back, axis=-1, keepdims=True)
    up = np.cross(lateral, back)
    base = origin + width * (0.19 * back - 0.30 * up)
    return base + 0.36 * width * lateral, base - 0.36 * width * lateral
