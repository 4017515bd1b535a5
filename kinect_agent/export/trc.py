"""OpenSim marker file (.trc, PathFileType 4) of a recording's joint centres, one marker per joint.

Layout (tab-separated, as OpenSim's TRCFileAdapter reads it):
    PathFileType  4  (X/Y/Z)  <file name>
    DataRate  CameraRate  NumFrames  NumMarkers  Units  OrigDataRate  OrigDataStartFrame  OrigNumFrames
    <values of the line above>
    Frame#  Time  <marker 1>  ""  ""  <marker 2> ...
    ""  ""  X1  Y1  Z1  X2  Y2  Z2 ...
    (blank line)
    <frame number from 1>  <time s>  <x y z per marker, mm>
Coordinates are millimetres in the camera frame (x side, y up as OpenSim expects, z away from the camera); a marker
not tracked in a frame has empty cells, which OpenSim reads as missing. Time is the recording's own time from 0;
DataRate is the median frame rate. Marker names are the skeleton's joint names (skeleton.JOINTS).
"""

from __future__ import annotations

import io

import numpy as np

from kinect_agent import skeleton

MM_PER_M = 1000.0


def data_rate(t: np.ndarray) -> float:
    """Returns the median frame rate (Hz) of times t (T,) s; 30 for a single frame."""
    return float(1.0 / np.median(np.diff(t))) if t.shape[0] > 1 else 30.0


def write_text(t: np.ndarray, positions: np.ndarray, file_name: str = "session.trc") -> str:
    """Returns the TRC text of joint centres.

    t: (T,) s, increasing. positions: (T, J, 3) m, camera frame, NaN = untracked (written as empty cells).
    """
    t = np.asarray(t, dtype=np.float64)
    positions = np.asarray(positions, dtype=np.float64)
    if positions.ndim != 3 or positions.shape[1:] != (skeleton.J, 3) or positions.shape[0] != t.shape[0]:
        raise ValueError(f"positions must have shape ({t.shape[0]}, {skeleton.J}, 3), got {positions.shape}")
    n = t.shape[0]
    rate = data_rate(t)
    out = io.StringIO()
    out.write(f"PathFileType\t4\t(X/Y/Z)\t{file_name}\n")
    out.write("DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames\n")
    out.write(f"{rate:.6f}\t{rate:.6f}\t{n}\t{skeleton.J}\tmm\t{rate:.6f}\t1\t{n}\n")
    out.write("Frame#\tTime\t" + "\t".join(f"{name}\t\t" for name in skeleton.JOINTS).rstrip("\t") + "\n")
    out.write("\t\t" + "\t".join(f"X{k}\tY{k}\tZ{k}" for k in range(1, skeleton.J + 1)) + "\n")
    out.write("\n")
    mm = positions.reshape(n, -1) * MM_PER_M
    t0 = t - t[0] if n else t
    for i in range(n):
        cells = ["" if not np.isfinite(v) else f"{v:.3f}" for v in mm[i]]
        out.write(f"{i + 1}\t{t0[i]:.6f}\t" + "\t".join(cells) + "\n")
    return out.getvalue()
