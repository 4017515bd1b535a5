"""Sustained tracking loss: a joint that jumps away faster than a body moves, stays away, and jumps back.

Real Kinect v2 failures (KERAAL Kinect + Vicon pairs, bench/real_pairs.py) are often plateaus, not spikes: a wrist held
0.9 m off at head height for 1.4 s, a whole arm 0.3-0.8 m off for 1.2 s. The temporal residual of outliers.py judges
a sample against its 0.5 s neighbourhood, so a plateau 2-3 windows long looks smooth and is kept. Here, per joint:

    jump     the speed between consecutive present samples exceeds the joint's limit (JOINT_SPEED_LIMIT_M_S:
             2 m/s trunk, 3 m/s elbows and knees, 4 m/s wrists, ankles, hands, feet); jump frames less than
             JUMP_GAP_FRAMES apart form one jump event (the SDK often takes 2-3 frames to jump)
    away     an event that carries the joint at least min_dev_m from the last sample before it (frame a)
    back     a later event, at least min_len_s after it ends and within max_len_s of its start, that ends at
             frame b close to where the joint left (|p[b] - p[a]| <= RETURN_FRACTION of the jump away)
    far      the samples between a and b sit, in median, at least min_dev_m from the straight line p[a] -> p[b]

Every sample strictly between a and b is then an outlier (probability 1). Kept off by default
(PipelineConfig.outlier_excursions), measured 2026-11-23:
    real KERAAL pairs (3 trials, one subject; also where the thresholds were chosen): flags 224 of 3 477
        well-estimated joint-frames (temporal step alone: 50); offline RMSE against Vicon 128.6 -> 85.7 mm, elbow
        angle RMSE 33.5 -> 22.4 deg, the paper's outlier gain (SD) 3 -> 20 %.
    bench/accuracy.py (simulated Kinect errors on CMU, HDM05 and the simulator): precision 0.916 -> 0.708 at the
        same recall, offline RMSE 119.3 -> 120.9 mm. Fast true motion (HDM05 arm circles and kicks reach 9-13 m/s at
        the hand) and the simulator's own gross excursions (kinect_noise: direction swings of 0.2-0.7 m that its
        truth counts as clean) both look like this pattern.
So it helps on real recordings of slow exercises and hurts on fast motion; it is an option, not the default.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from kinect_agent import skeleton
from kinect_agent.recording import Recording
from kinect_agent.skeleton import NOT_TRACKED

if TYPE_CHECKING:
    from kinect_agent.processing.pipeline import PipelineConfig

_TRUNK = {"ROOT", "SPINE", "NECK", "HEAD", "SHO_L", "SHO_R", "HIP_L", "HIP_R"}
_MIDDLE = {"ELB_L", "ELB_R", "KNE_L", "KNE_R"}
JOINT_SPEED_LIMIT_M_S = np.array([2.0 if n in _TRUNK else 3.0 if n in _MIDDLE else 4.0 for n in skeleton.JOINTS])
JUMP_GAP_FRAMES = 3
RETURN_FRACTION = 0.5


def jump_events(t: np.ndarray, p: np.ndarray, speed_limit: float) -> list[tuple[int, int]]:
    """Returns [(first, last)] frame indices of the jump events of one joint, in time order.

    t: (T,) s. p: (T, 3) m, NaN = missing. A frame i is a jump frame when p[i - 1] and p[i] are both present and
    |p[i] - p[i - 1]| / (t[i] - t[i - 1]) > speed_limit (m/s); jump frames at most JUMP_GAP_FRAMES apart are merged.
    """
    ok = np.all(np.isfinite(p), axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        speed = np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(t)
    jumps = np.flatnonzero(ok[1:] & ok[:-1] & (speed > speed_limit)) + 1
    events: list[list[int]] = []
    for i in jumps:
        if events and i - events[-1][1] <= JUMP_GAP_FRAMES:
            events[-1][1] = int(i)
        else:
            events.append([int(i), int(i)])
    return [(a, b) for a, b in events]


def _bridge_deviation(t: np.ndarray, p: np.ndarray, a: int, b: int) -> float:
    """Median distance (m) of p[a+1 .. b-1] from the straight line p[a] -> p[b], linear in time; NaN if none."""
    frac = ((t[a + 1 : b] - t[a]) / (t[b] - t[a]))[:, None]
    dev = np.linalg.norm(p[a + 1 : b] - (p[a] + frac * (p[b] - p[a])), axis=1)
    return float(np.nanmedian(dev)) if np.any(np.isfinite(dev)) else float("nan")


def find_excursions(
    t: np.ndarray,
    p: np.ndarray,
    speed_limit: float,
    min_dev_m: float = 0.2,
    min_len_s: float = 0.3,
    max_len_s: float = 3.0,
) -> list[tuple[int, int]]:
    """Returns [(a, b)]: the excursions of one joint; the samples a+1 .. b-1 are away (module docstring).

    t: (T,) s. p: (T, 3) m, NaN = missing. Excursions do not overlap; each away-jump takes the first back-jump that
    qualifies.
    """
    events = jump_events(t, p, speed_limit)
    ok = np.all(np.isfinite(p), axis=1)
    found: list[tuple[int, int]] = []
    for k, (s1, e1) in enumerate(events):
        a = s1 - 1
        if (found and a < found[-1][1]) or not ok[a]:
            continue
        away = float(np.linalg.norm(p[e1] - p[a]))
        if away < min_dev_m:
            continue
        for s2, b in events[k + 1 :]:
            if t[b] - t[s1] > max_len_s:
                break
            if t[s2] - t[e1] < min_len_s - 1e-6 or np.linalg.norm(p[b] - p[a]) > RETURN_FRACTION * away:
                continue
            if _bridge_deviation(t, p, a, b) >= min_dev_m:
                found.append((a, b))
                break
    return found


def excursion_probabilities(rec: Recording, config: PipelineConfig | None = None) -> np.ndarray:
    """Returns (T, J) in {0, 1}: 1 for the samples inside an excursion and where the joint is not tracked.

    Uses config.excursion_min_dev_m, excursion_min_len_s and excursion_max_len_s.
    """
    from kinect_agent.processing.pipeline import PipelineConfig

    config = config or PipelineConfig()
    positions = np.where((rec.state != NOT_TRACKED)[..., None], rec.positions, np.nan)
    prob = np.where(rec.state == NOT_TRACKED, 1.0, 0.0)
    for j in range(positions.shape[1]):
        spans = find_excursions(
            rec.t, positions[:, j], float(JOINT_SPEED_LIMIT_M_S[j]), config.excursion_min_dev_m,
            config.excursion_min_len_s, config.excursion_max_len_s,
        )  # fmt: skip
        for a, b in spans:
            prob[a + 1 : b, j] = 1.0
    return prob
