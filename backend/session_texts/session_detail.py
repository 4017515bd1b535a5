"""The evidence behind one session's numbers, for the therapist's session page: angle curves, repetition speeds,
hand paths.

Definitions:
    angle curves  = the exercise's defining angles (body.angles.joint_angles: the one definition the range
                    of motion, its intervals and the exported tables use), degrees, over time in seconds from the
                    first frame. "raw": computed from the raw recording frame by frame (NaN where a joint is
                    untracked); "filtered": the measured angles (angles.measured_angles: the filtered recording,
                    gap-filled and smoothed, as report.analyze_recording measures it). Both lie in the angle's
                    domain (angles.DOMAIN_DEG; nothing is unwrapped) and are NaN (a gap) where the angle is
                    undefined. Each curve is thinned by min/max decimation to at most
                    MAX_CURVE_POINTS points: the samples are cut into MAX_CURVE_POINTS / 2 equal runs and each
                    run keeps its lowest and its highest sample, in time order, so peaks and troughs stay exact;
    peak speed    = the largest |dθ/dt| (deg/s, central differences of the conditioned series series.smooth) of
                    the repetition's angles between its start and end: the angle of its side, both sides' angles
                    for "both" or "center";
    hand path     = reachable.hand_path: the hand relative to the shoulder in the trunk frame (outward, up,
                    forward), in arm lengths, thinned by plain decimation to at most MAX_PATH_POINTS points.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from backend.i18n import ENGLISH, N_, Translator
from kinect_agent.analysis import angles as analysis_angles
from kinect_agent.analysis import series
from kinect_agent.analysis.document import RepetitionItem
from kinect_agent.analysis.reachable import hand_path
from kinect_agent.body.angles import body_frame, joint_angles

MAX_CURVE_POINTS = 1500
MAX_PATH_POINTS = 600
ARM_PREFIXES = ("shoulder_", "elbow_")
# each angle of kinect_agent.body.angles.ANGLE_NAMES in words, side included (a whole message each: the side's word
# agrees with the joint in German, Spanish and French); the curves' labels are written in the reader's language
ANGLE_WORDS = {
    "elbow_flexion_L": N_("left elbow flexion"), "elbow_flexion_R": N_("right elbow flexion"),
    "knee_flexion_L": N_("left knee flexion"), "knee_flexion_R": N_("right knee flexion"),
    "shoulder_flexion_L": N_("left shoulder flexion"), "shoulder_flexion_R": N_("right shoulder flexion"),
    "shoulder_abduction_L": N_("left shoulder abduction"), "shoulder_abduction_R": N_("right shoulder abduction"),
    "shoulder_rotation_L": N_("left shoulder rotation"), "shoulder_rotation_R": N_("right shoulder rotation"),
    "hip_flexion_L": N_("left hip flexion"), "hip_flexion_R": N_("right hip flexion"),
    "hip_abduction_L": N_("left hip abduction"), "hip_abduction_R": N_("right hip abduction"),
    "trunk_flexion": N_("trunk flexion"), "trunk_lateral_flexion": N_("trunk lateral flexion"),
}  # fmt: skip
# the curves' kinds in words (TRANSLATORS: said of an angle's curve: "right knee flexion, filtered")
CURVE_KINDS = {"raw": N_("raw"), "filtered": N_("filtered"), "smoothed": N_("smoothed")}
CURVE_LABEL = N_("%(angle)s, %(kind)s")  # TRANSLATORS: an angle's curve in a chart's legend: "right knee flexion, raw"


def minmax_indices(y: np.ndarray, max_points: int = MAX_CURVE_POINTS) -> np.ndarray:
    """Returns the sorted sample indices (K,) int, K ≤ max_points, that min/max decimation keeps of y: (T,).

    NaN samples are skipped; a run with no finite sample keeps its first sample (so a gap stays a gap). Raises
    ValueError when max_points < 2 or y is not 1-D.
    """
    y = np.asarray(y, dtype=np.float64)
    if y.ndim != 1:
        raise ValueError(f"y must have shape (T,), got {y.shape}")
    if max_points < 2:
        raise ValueError(f"max_points must be at least 2, got {max_points}")
    T = y.shape[0]
    if T <= max_points:
        return np.arange(T)
    n_runs = max_points // 2
    size = -(-T // n_runs)
    padded = np.full(n_runs * size, np.nan)
    padded[:T] = y
    runs = padded.reshape(n_runs, size)
    finite = np.isfinite(runs)
    lo = np.where(finite, runs, np.inf).argmin(axis=1)
    hi = np.where(finite, runs, -np.inf).argmax(axis=1)
    starts = np.arange(n_runs) * size
    keep = np.concatenate((starts + lo, starts + hi))
    return np.unique(keep[keep < T])


def _rounded(values: np.ndarray, digits: int) -> list[float | None]:
    """Returns values (K,) rounded, as a JSON-ready list with None for NaN."""
    out = np.round(np.asarray(values, dtype=np.float64), digits)
    return [None if not np.isfinite(v) else float(v) for v in out]


def curve(t_s: np.ndarray, deg: np.ndarray, max_points: int = MAX_CURVE_POINTS) -> dict[str, list[float | None]]:
    """Returns {"t_s", "deg"}: one angle series thinned by min/max decimation (module doc).

    t_s: (T,) s from the session start; deg: (T,) degrees, NaN = unknown (sent as null).
    """
    idx = minmax_indices(deg, max_points)
    return {"t_s": _rounded(t_s[idx], 3), "deg": _rounded(deg[idx], 1)}


def measured_angles(t: np.ndarray, positions: np.ndarray, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    """Returns {name: (T,) degrees} of the angles `names` as the analysis measures them.

    t: (T,) s. positions: (T, J, 3) m, camera frame, the measured (filtered) positions; they are gap-filled and
    smoothed first (angles.measured_angles), as report.analyze_recording does.
    """
    angles = analysis_angles.measured_angles(t, positions).angles
    return {name: angles[name] for name in names}


def angle_label(name: str, t: Translator = ENGLISH) -> str:
    """Returns an angle name in words in t's language: "knee_flexion_R" -> "right knee flexion" ("Beugung des
    rechten Knies"); a name outside ANGLE_WORDS with its underscores as spaces."""
    words = ANGLE_WORDS.get(name)
    return t.gettext(words) if words is not None else name.replace("_", " ")


def curve_words(angle: str, kind: str, t: Translator = ENGLISH) -> dict[str, str]:
    """Returns a curve's words in t's language: {"label": "right knee flexion, raw", "angle_label": "right knee
    flexion", "kind_label": "raw"}."""
    angle_words = angle_label(angle, t)
    kind_words = t.gettext(CURVE_KINDS[kind]) if kind in CURVE_KINDS else kind
    return {"label": t.gettext(CURVE_LABEL, angle=angle_words, kind=kind_words), "angle_label": angle_words,
            "kind_label": kind_words}  # fmt: skip


def angle_curves(
    t: np.ndarray,
    raw: np.ndarray,
    measured_deg: dict[str, np.ndarray],
    names: tuple[str, ...],
    measured_kind: str = "filtered",
) -> list[dict[str, Any]]:
    """Returns [{"angle", "kind", "label", "angle_label", "kind_label", "t_s", "deg"}]: per defining angle, the raw
    curve then the measured one (the words in English: curve_words rewrites them for a reader).

    t: (T,) s. raw: (T, J, 3) m, camera frame, NaN = untracked. measured_deg: measured_angles' output for the
    same frames. measured_kind names the second curve ("filtered", or "smoothed" when the session has no
    filtered recording and the raw one was measured).
    """
    t_s = np.asarray(t, dtype=np.float64) - float(t[0])
    raw_angles = joint_angles(raw)
    out = []
    for name in names:
        for kind, deg in (("raw", raw_angles[name]), (measured_kind, measured_deg[name])):
            out.append({"angle": name, "kind": kind, **curve_words(name, kind), **curve(t_s, deg)})
    return out


def _rep_angles(side: str, names: tuple[str, ...]) -> tuple[str, ...]:
    """Returns the angles of names a repetition of this side ("left", "right", "both", "center") moved."""
    suffix = {"left": "_L", "right": "_R"}.get(side)
    own = tuple(n for n in names if suffix is not None and n.endswith(suffix))
    return own or names


def angular_speeds(t: np.ndarray, angles: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Returns {name: (T,) deg/s}, |dθ/dt| of each conditioned angle (series.smooth); t: (T,) s."""
    if t.shape[0] < 2:
        return {name: np.zeros_like(t) for name in angles}
    return {name: np.abs(np.gradient(series.smooth(t, y), t)) for name, y in angles.items()}


def peak_speeds(t: np.ndarray, speeds: dict[str, np.ndarray], repetitions: Sequence[RepetitionItem]
                ) -> list[float | None]:  # fmt: skip
    """Returns the peak speed (deg/s, 0.1) of each repetition, read between its start_s and end_s on its side's
    angles (module doc).

    t: (T,) s; speeds: angular_speeds' output; repetition times are seconds from t[0]. None when no angle of the
    repetition has a finite speed inside it.
    """
    t_s = np.asarray(t, dtype=np.float64) - float(t[0])
    names = tuple(speeds)
    out: list[float | None] = []
    for rep in repetitions:
        inside = (t_s >= rep.start_s - 1e-6) & (t_s <= rep.end_s + 1e-6)
        values = [speeds[n][inside] for n in _rep_angles(rep.side, names)]
        values = [v[np.isfinite(v)] for v in values]
        best = max((float(v.max()) for v in values if v.size), default=None)
        out.append(None if best is None else round(best, 1))
    return out


def is_arm_exercise(names: tuple[str, ...]) -> bool:
    """Returns whether the defining angles `names` move the arms (shoulder or elbow angles)."""
    return any(n.startswith(ARM_PREFIXES) for n in names)


def hand_paths(
    measured: np.ndarray, t: np.ndarray, max_points: int = MAX_PATH_POINTS
) -> dict[str, dict[str, Any] | None]:
    """Returns {"left", "right"}: {"arm_length_m", "outward", "up", "forward"} lists in arm lengths, or None.

    measured: (T, J, 3) m, camera frame, the measured positions (smoothed as the analysis does); t: (T,) s.
    Frames where the hand is unknown are left out; at most max_points frames, evenly spaced, are kept.
    """
    smoothed = series.smooth_positions(t, measured)
    frame = body_frame(smoothed)
    out: dict[str, dict[str, Any] | None] = {}
    for key, side in (("left", "L"), ("right", "R")):
        path = hand_path(smoothed, side, frame)
        if path is None:
            out[key] = None
            continue
        h, length = path
        h = h[np.all(np.isfinite(h), axis=1)]
        step = max(1, -(-h.shape[0] // max_points))
        h = h[::step]
        out[key] = {"arm_length_m": round(length, 3)} | {
            axis: _rounded(h[:, k], 3) for k, axis in enumerate(("outward", "up", "forward"))
        }
    return out
