"""Reachable workspace of each hand, relative to the arm's length (after Kurillo et al., "Evaluation of upper
extremity reachable workspace using Kinect camera", Technology and Health Care 21, 2013).

Definition, per side:
    1. the hand vector h = HAN − SHO in the trunk frame of angles.body_frame (x outward from that side, y up,
       z forward), divided by the arm length L = median over frames of |SHO−ELB| + |ELB−WRI| + |WRI−HAN| (m);
    2. the frontal hemisphere of directions around the shoulder (z ≥ 0; the camera cannot see the hand behind the
       body) is cut into cells of CELL_DEG × CELL_DEG in azimuth (from forward towards outward, −90..90°) and
       elevation (from horizontal towards up, −90..90°); each cell's solid angle is Δaz · (sin el₂ − sin el₁);
    3. a cell is reached when a hand direction falls in it while the hand is at least MIN_REACH (0.5) arm lengths
       from the shoulder (a bent arm close to the body does not sweep the workspace envelope);
    4. area_ratio = solid angle of the reached cells / 2π (the unit hemisphere's area: Kurillo's relative
       surface area), in [0, 1]; quadrants: the same ratio within each quarter of the hemisphere
       (upper/lower × lateral/medial, each of solid angle π/2);
       volume_ratio = Σ over reached cells of r³/3 · Ω_cell / (2π/3), r = the farthest normalised reach seen in
       that cell (at most 1): the reached volume relative to a hemisphere of radius L, in [0, 1].
A side whose hand, elbow or shoulder is never tracked reads None.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from kinect_agent.analysis import series
from kinect_agent.body.angles import body_frame
from kinect_agent.skeleton import INDEX

CELL_DEG = 10.0
MIN_REACH = 0.5
_N = int(round(180.0 / CELL_DEG))
_EDGES = np.radians(np.linspace(-90.0, 90.0, _N + 1))
_CELL_SR = np.diff(_EDGES)[None, :] * np.diff(np.sin(_EDGES))[:, None]  # (el, az) steradians; sums to 2π


def _arm_length(p: np.ndarray, side: str) -> float:
    chain = [INDEX[f"{j}_{side}"] for j in ("SHO", "ELB", "WRI", "HAN")]
    seg = series.norm3(np.diff(p[:, chain], axis=1)).sum(axis=1)
    seg = seg[np.isfinite(seg)]
    return float(np.median(seg)) if seg.size else float("nan")


def _quadrants(reached: np.ndarray) -> dict[str, float]:
    """reached: (el, az) bool cells; azimuth > 0 is lateral, elevation > 0 is up."""
    half = _N // 2
    area = np.where(reached, _CELL_SR, 0.0)
    q = {
        "upper_lateral": area[half:, half:],
        "upper_medial": area[half:, :half],
        "lower_medial": area[:half, :half],
        "lower_lateral": area[:half, half:],
    }
    return {name: round(float(a.sum() / (np.pi / 2)), 4) for name, a in q.items()}


Frame = tuple[np.ndarray, np.ndarray, np.ndarray]


def hand_path(positions: np.ndarray, side: str, frame: Frame | None = None) -> tuple[np.ndarray, float] | None:
    """Returns (h (T, 3), L m): the hand HAN − SHO of one side ("L" or "R") in the trunk frame (outward, up,
    forward), in arm lengths L (step 1 of the module doc), NaN where untracked; None when L is unknown.

    positions: (T, J, 3) m, camera frame. frame: (up, left, forward), each (T, 3), of angles.body_frame(positions)
    when already computed.
    """
    p = np.asarray(positions, dtype=np.float64)
    L = _arm_length(p, side)
    if not np.isfinite(L) or L <= 0:
        return None
    up, left, forward = body_frame(p) if frame is None else frame
    outward = left if side == "L" else -left
    h = p[:, INDEX[f"HAN_{side}"]] - p[:, INDEX[f"SHO_{side}"]]
    return np.stack([series.dot3(h, axis) / L for axis in (outward, up, forward)], axis=-1), L


def side_workspace(positions: np.ndarray, side: str, frame: Frame | None = None) -> dict[str, Any] | None:
    """Returns the workspace metrics of one side ("L" or "R") for positions (T, J, 3) m, camera frame.

    frame: (up, left, forward), each (T, 3), of angles.body_frame(positions) when already computed.
    """
    path = hand_path(positions, side, frame)
    if path is None:
        return None
    h, L = path
    x, y, z = h[:, 0], h[:, 1], h[:, 2]
    r = np.sqrt(x**2 + y**2 + z**2)
    use = np.isfinite(r) & (r >= MIN_REACH) & (z >= 0)
    el = np.arcsin(np.clip(y[use] / r[use], -1.0, 1.0))
    az = np.arctan2(x[use], z[use])
    i = np.clip(np.searchsorted(_EDGES, el, side="right") - 1, 0, _N - 1)
    k = np.clip(np.searchsorted(_EDGES, az, side="right") - 1, 0, _N - 1)
    reach = np.zeros((_N, _N))
    np.maximum.at(reach, (i, k), np.minimum(r[use], 1.0))
    reached = reach > 0
    return {
        "arm_length_m": round(L, 3),
        "area_ratio": round(float(_CELL_SR[reached].sum() / (2 * np.pi)), 4),
        "volume_ratio": round(float(np.sum(reach**3 / 3.0 * _CELL_SR) / (2 * np.pi / 3)), 4),
        "quadrants": _quadrants(reached),
    }


def reachable_range(positions: np.ndarray, frame: Frame | None = None) -> dict[str, dict[str, Any] | None]:
    """Returns {"left": ..., "right": ...} workspace metrics (see module doc) of positions (T, J, 3) m."""
    frame = body_frame(np.asarray(positions, dtype=np.float64)) if frame is None else frame
    return {"left": side_workspace(positions, "L", frame), "right": side_workspace(positions, "R", frame)}
