"""Kinect measurement errors calibrated on the paper's accuracy tables (Wang et al., section 3.1).

What the tabled per-joint "mean" and "SD" mean here (and how tests compute the simulated statistic):
    d(t) = |measured(t) - truth(t)|, the Euclidean offset distance of one joint in one frame, metres;
    mean = mean of d over the frames of a session, SD = standard deviation of d over those frames,
    counting only frames whose state is TRACKED and that are not tracking-loss outliers (the frames the
    paper's mixture-model outlier removal keeps).

Model of the offset of joint j (the Gaussian component of the paper's mixture), see gaussian_offsets():
    |offset_j(t)| = |mu_j + sigma_j · z_j(t)|, z_j an AR(1) (discretised Ornstein-Uhlenbeck) process of unit
    variance with correlation time TAU_S, 70 % of its variance shared by all joints, the rest correlated 0.8 with the
    parent joint's (neighbouring joints err together). That distance is a folded normal; mu_j and sigma_j are solved
    so its mean and SD equal the table (all tabled SD/mean ratios are below the folded normal's limit of 0.756). The
    direction is chosen so that the segments carry the tabled length errors (below); it never changes the distance.
Tracking loss (the uniform component): bursts of 0.07-0.2 s in which a joint jumps, every frame anew, from the
    Kinect's own (biased) estimate truth + offset in a random direction, by a length uniform over an interval (the
    physical choice: a lost joint is thrown from where the Kinect would have put it; before issue 24 the jumps
    started at the truth). Rate and length are solved per joint and setting from the paper's mean and SD gains of
    removing the outliers (outlier_removal_gain_pct.csv; outlier_law): 0.3-10 % of the joint-frames (median 3.7 %),
    jumps of 0.05-1.7 m (median 0.24 m), in non-overlapping bursts covering exactly that fraction (_exact_bursts).
    Where the joint's offset is large and steady (Kinect 1's hips) no such law reaches the tabled mean gain at the
    tabled SD gain; the SD gain is met and the mean gain falls short there (bench/README.md, issue 24 decision 4).
    Inferred joints (state 1) carry an extra offset of 1.5 table SDs; not-tracked joints (state 0) are NaN.
Bone-length errors (see gaussian_offsets): each bone aims at true length + a commanded error (mean + SD · AR(1));
    a greedy pass down the tree puts each child where its distance sphere meets the wanted-length sphere around the
    measured parent, then alternating projections (refine_offsets) trade the errors between neighbouring bones while
    every joint stays exactly on its distance sphere. A few calibration rounds on a subsample (_commanded_errors) aim
    past the table where the spheres cannot carry the tabled error, so the achieved mean and SD match it.
    bone_length_error() computes the simulated statistic; tests/kinect_agent/sources/test_bone_length_error.py
    checks it per setting.
Known limits: gross excursions of the Gaussian component (clean joint-frames far from their running median, not in
    the outlier mask: bench/accuracy.py reports them as precision_incl_gross), and a few segments that miss the
    table (Kinect 1 PELVIC). How well each part matches the tables: bench/README.md, "The simulator's calibration
    (kinect_noise)".
"""

from __future__ import annotations

import csv
import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
from scipy.optimize import brentq
from scipy.special import erf

from kinect_agent import skeleton
from kinect_agent.errors import AgentError
from kinect_agent.recording import Recording
from kinect_agent.skeleton import INFERRED, NOT_TRACKED, TRACKED
from kinect_agent.sources import _kinect_noise_numba

CALIBRATION_DIR = Path(__file__).parent / "calibration"
TABLE_FILES = (
    "joint_offset_sitting_mm.csv",
    "joint_offset_standing_mm.csv",
    "bone_length_error_sitting_mm.csv",
    "bone_length_error_standing_mm.csv",
    "outlier_removal_gain_pct.csv",
)
DEVICES = ("kinect1", "kinect2")
VIEWS = (0, 30, 60)
POSES = ("sitting", "standing")
TAU_S = 0.2  # correlation time of the jitter, seconds
JITTER_PARENT_CORR = 0.8  # correlation of a joint's own jitter with its parent's (neighbours err together)
JITTER_SHARED = 0.7  # share of the jitter variance common to all joints (the whole skeleton wobbles together)
INFERRED_BASE = 0.006  # fraction of joint-frames flagged inferred, same scaling
NOT_TRACKED_BASE = 0.0015  # fraction of joint-frames lost (NaN), same scaling


class SimulationError(AgentError, ValueError):
    """A simulation was asked for with an impossible or unknown setting."""


@dataclass(frozen=True)
class Tables:
    """The paper's tables, metres. Keys (device, pose, view_deg); arrays in JOINTS / SEGMENT_NAMES order.

    offset_mean, offset_sd: (J,) mean and SD of the per-frame Euclidean offset distance to mocap.
    bone_mean, bone_sd: (14,) mean and SD of the segment-length difference to mocap (measured - mocap).
    gain_pct: (device, pose, view) -> (mean gain, SD gain) in % after outlier removal.
    """

    offset_mean: dict[tuple[str, str, int], np.ndarray]
    offset_sd: dict[tuple[str, str, int], np.ndarray]
    bone_mean: dict[tuple[str, str, int], np.ndarray]
    bone_sd: dict[tuple[str, str, int], np.ndarray]
    gain_pct: dict[tuple[str, str, int], tuple[float, float]]


def _read_rows(path: Path) -> list[dict[str, str]]:
    with open(path, encoding="utf-8", newline="") as f:
        return list(csv.DictReader(f))


def _per_item(
    path: Path, key: str, names: tuple[str, ...]
) -> tuple[dict[tuple[str, int], np.ndarray], dict[tuple[str, int], np.ndarray]]:
    rows = {r[key]: r for r in _read_rows(path)}
    missing = [n for n in names if n not in rows]
    if missing:
        raise SimulationError(f"{path}: rows missing for {', '.join(missing)}")
    mean: dict[tuple[str, int], np.ndarray] = {}
    sd: dict[tuple[str, int], np.ndarray] = {}
    for dev, prefix in (("kinect1", "k1"), ("kinect2", "k2")):
        for view in VIEWS:
            mean[dev, view] = np.array([float(rows[n][f"{prefix}_mean_{view}"]) for n in names]) / 1000.0
            sd[dev, view] = np.array([float(rows[n][f"{prefix}_sd_{view}"]) for n in names]) / 1000.0
    return mean, sd


@lru_cache(maxsize=4)
def load_tables(directory: str | Path | None = None) -> Tables:
    """Returns the calibration tables, from the package copies (or from `directory`, same file names)."""
    base = Path(directory) if directory is not None else CALIBRATION_DIR
    om, osd, bm, bsd, gain = {}, {}, {}, {}, {}
    for pose in POSES:
        m, s = _per_item(base / f"joint_offset_{pose}_mm.csv", "joint", skeleton.JOINTS)
        b, bs = _per_item(base / f"bone_length_error_{pose}_mm.csv", "segment", skeleton.SEGMENT_NAMES)
        for dev, view in m:
            om[dev, pose, view], osd[dev, pose, view] = m[dev, view], s[dev, view]
            bm[dev, pose, view], bsd[dev, pose, view] = b[dev, view], bs[dev, view]
    for row in _read_rows(base / "outlier_removal_gain_pct.csv"):
        for view in VIEWS:
            gain[row["device"], row["pose"], view] = (float(row[f"mean_gain_{view}"]), float(row[f"sd_gain_{view}"]))
    return Tables(om, osd, bm, bsd, gain)


def _folded_mean(lam: np.ndarray) -> np.ndarray:
    """Mean of |N(lam, 1)|."""
    return np.sqrt(2.0 / np.pi) * np.exp(-0.5 * lam**2) + lam * erf(lam / np.sqrt(2.0))


FOLDED_MAX_RATIO = float(np.sqrt(1.0 - 2.0 / np.pi) / np.sqrt(2.0 / np.pi))  # SD/mean of |N(0, 1)|


def folded_normal_parameters(mean: np.ndarray, sd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Returns (mu, sigma), each like `mean`, such that |N(mu, sigma)| has the given mean and SD.

    mean, sd: (...,) float, any unit, mean > 0, sd >= 0. Ratios sd/mean above 0.756 are impossible for a folded
    normal and raise SimulationError.
    """
    mean, sd = np.broadcast_arrays(np.asarray(mean, float), np.asarray(sd, float))
    mu, sigma = np.empty(mean.shape), np.empty(mean.shape)
    for idx in np.ndindex(mean.shape):
        m, s = float(mean[idx]), float(sd[idx])
        ratio = s / m
        if not ratio < FOLDED_MAX_RATIO:
            raise SimulationError(
                f"offset SD/mean = {ratio:.3f} exceeds the folded-normal limit {FOLDED_MAX_RATIO:.3f}"
            )
        if ratio < 1e-6:
            mu[idx], sigma[idx] = m, s
            continue

        def gap(lam: float, ratio: float = ratio) -> float:
            fm = float(_folded_mean(np.array(lam)))
            return np.sqrt(max(1.0 + lam**2 - fm**2, 0.0)) / fm - ratio

        lam = brentq(gap, 0.0, 1e3 if ratio > 1e-3 else 1e7, xtol=1e-12)
        sigma[idx] = m / float(_folded_mean(np.array(lam)))
        mu[idx] = lam * sigma[idx]
    return mu, sigma


def ar1(rng: np.random.Generator, T: int, n: int, dt: float, tau: float = TAU_S) -> np.ndarray:
    """Returns (T, n) unit-variance AR(1) noise with correlation exp(-dt / tau) per frame (stationary from frame 0)."""
    phi = np.exp(-dt / tau)
    innov = rng.standard_normal((T, n)) * np.sqrt(1.0 - phi**2)
    z = np.empty((T, n))
    z[0] = rng.standard_normal(n)
    for i in range(1, T):
        z[i] = phi * z[i - 1] + innov[i]
    return z


def _unit_vectors(rng: np.random.Generator, n: int) -> np.ndarray:
    v = rng.standard_normal((n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


_DISTAL = {"WRI": 2.0, "HAN": 2.2, "ANK": 2.0, "FOO": 2.2, "ELB": 1.4, "KNE": 1.4, "HEAD": 1.0}


def loss_weights(device: str, view_deg: int) -> np.ndarray:
    """Returns (J,) multipliers of the tracking-loss rates: distal joints, Kinect 1 and wide views lose more."""
    per_joint = np.array([_DISTAL.get(n.split("_")[0], 0.7) for n in skeleton.JOINTS])
    return per_joint * (1.0 + view_deg / 60.0) * (1.3 if device == "kinect1" else 1.0)


OUTLIER_FRACTION_MAX = 0.1  # at most this fraction of a joint's frames is tracking loss
OUTLIER_HALF_WIDTH = 0.5  # a jump's length is uniform over jump · [1 − h, 1 + h], h this
_HERMITE_NODES = 64  # Gauss-Hermite nodes over the clean offset distance (jump_moments)
_JUMP_RANGE_M = (1e-3, 4.0)  # the jump lengths outlier_law searches
_BISECTIONS = 40


def _jump_antiderivative(a: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Returns ∫_0^r g(a, s) ds, g(a, s) = E_u |a·e + s·u| = max(a, s) + min(a, s)² / (3 · max(a, s)) (u uniform on
    the sphere, e a fixed unit vector); a, r: broadcastable arrays, metres, a ≥ 0, r ≥ 0."""
    a = np.maximum(a, 1e-12)
    inside = a * r + r**3 / (9.0 * a)  # r ≤ a
    beyond = a**2 * (10.0 / 9.0) + 0.5 * (r**2 - a**2) + (a**2 / 3.0) * np.log(np.maximum(r, a) / a)  # r > a
    return np.where(r <= a, inside, beyond)


def jump_moments(mean: np.ndarray, sd: np.ndarray, jump: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Returns (e, v), each (J, K) m and m²: E[D] − mean and E[(D − mean)²] of an outlier's distance to the truth.

    mean, sd: (J,) m, the clean offset distance |o| (a folded normal with this mean and SD); jump: (J, K) m. An outlier
    is truth + o + R·u, u uniform on the sphere, R uniform over jump·[1 − h, 1 + h] (h = OUTLIER_HALF_WIDTH), so
    D = |o + R·u|: E[D²] = mean² + sd² + E[R²] exactly (u independent of o), E[D] exact in R and u
    (_jump_antiderivative) and Gauss-Hermite over |o|.
    """
    mu, sigma = folded_normal_parameters(mean, sd)
    z, w = np.polynomial.hermite_e.hermegauss(_HERMITE_NODES)
    a = np.abs(mu[:, None, None] + sigma[:, None, None] * z)  # (J, 1, n)
    lo = (jump * (1.0 - OUTLIER_HALF_WIDTH))[..., None]
    hi = (jump * (1.0 + OUTLIER_HALF_WIDTH))[..., None]
    g = (_jump_antiderivative(a, hi) - _jump_antiderivative(a, lo)) / (hi - lo)  # E over R and u, (J, K, n)
    e = (g @ w) / np.sqrt(2.0 * np.pi) - mean[:, None]
    second = jump**2 * (1.0 + OUTLIER_HALF_WIDTH**2 / 3.0)  # E[R²]
    return e, sd[:, None] ** 2 + second - 2.0 * mean[:, None] * e


def outlier_law(
    mean: np.ndarray, sd: np.ndarray, mean_gain_pct: float, sd_gain_pct: float
) -> tuple[np.ndarray, np.ndarray]:
    """Returns (fraction (J,), jump (J,) m): the tracking-loss rate of each joint and the typical length of its jumps
    from the Kinect's own (biased) estimate, solved so that removing the outliers lowers the mean offset distance by
    mean_gain_pct and its SD by sd_gain_pct, the paper's gains for the setting (outlier_removal_gain_pct.csv).

    mean, sd: (J,) m, the tabled offset distance of the clean (Gaussian) component. An outlier is truth + o + R·u:
    a tracking loss throws the joint away from where the Kinect would have put it (o, its biased offset), not from
    where the joint is; u uniform on the sphere, R uniform over jump·[1 − h, 1 + h]. With e, v the outlier distance's
    excess mean and second moment about the clean mean (jump_moments) and a fraction p of outliers:
        mean gain g_m:  p·e = mean·g_m / (1 − g_m)                                   (= A)
        SD gain g_s:    p·v − p·sd² − p²·e² = r·sd²,  r = (1 − g_s)⁻² − 1  (the mixture's exact variance)
    so with p = A / e: A·(v − sd²) / e = r·sd² + A², increasing in the jump (bisection). A jump in a random direction
    adds distance only to second order while it adds variance to first order ((v − sd²) / e ≥ about the mean offset),
    so where A·mean > r·sd² + A² (joints with a large, steady offset: Kinect 1's hips, 256 ± 20 mm) no law meets
    both gains; there, and where p would pass OUTLIER_FRACTION_MAX, p = OUTLIER_FRACTION_MAX and the jump is solved
    for the SD gain alone (the mean gain then falls short: the most a law of this shape reaches at that SD gain).
    """
    mean, sd = np.asarray(mean, float), np.asarray(sd, float)
    gm = np.clip(mean_gain_pct / 100.0, 1e-3, 0.5)
    gs = np.clip(sd_gain_pct / 100.0, 0.0, 0.95)
    a = mean * gm / (1.0 - gm)
    target = ((1.0 - gs) ** -2 - 1.0) * sd**2  # r·sd², m²

    def free(jump: np.ndarray) -> np.ndarray:
        e, v = jump_moments(mean, sd, jump[:, None])
        return a * (v[:, 0] - sd**2) / e[:, 0] - (target + a**2)

    def capped(jump: np.ndarray) -> np.ndarray:
        e, v = jump_moments(mean, sd, jump[:, None])
        p = OUTLIER_FRACTION_MAX
        return p * (v[:, 0] - sd**2) - p**2 * e[:, 0] ** 2 - target

    lo, hi = np.full(mean.shape, _JUMP_RANGE_M[0]), np.full(mean.shape, _JUMP_RANGE_M[1])
    feasible = free(lo) < 0.0
    jump = _bisect(free, lo, hi)
    e = jump_moments(mean, sd, jump[:, None])[0][:, 0]
    fraction = np.where(feasible, a / e, np.inf)
    cap = fraction > OUTLIER_FRACTION_MAX
    if np.any(cap):
        jump = np.where(cap, _bisect(capped, lo, hi), jump)
    return np.minimum(fraction, OUTLIER_FRACTION_MAX), jump


@lru_cache(maxsize=len(DEVICES) * len(POSES) * len(VIEWS))
def setting_outlier_law(device: str, pose: str, view_deg: int) -> tuple[np.ndarray, np.ndarray]:
    """Returns outlier_law's (fraction (J,), jump (J,) m) for a tabled setting, solved once per process (≈ 0.3 s);
    the arrays are read-only."""
    tables, key = load_tables(), (device, pose, view_deg)
    fraction, jump = outlier_law(tables.offset_mean[key], tables.offset_sd[key], *tables.gain_pct[key])
    fraction.flags.writeable = False
    jump.flags.writeable = False
    return fraction, jump


def _bisect(f: Callable[[np.ndarray], np.ndarray], lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Returns (J,) where each increasing f (vectorised over joints) crosses 0 in [lo, hi], geometric bisection (the
    end itself where f does not change sign)."""
    lo, hi = lo.copy(), hi.copy()
    for _ in range(_BISECTIONS):
        mid = np.sqrt(lo * hi)
        below = f(mid) < 0.0
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return np.sqrt(lo * hi)


def _bursts(rng: np.random.Generator, T: int, fraction: np.ndarray, rate_hz: float) -> np.ndarray:
    """Returns (T, J) bool: bursts of 0.07-0.2 s covering about `fraction` (J,) of the frames of each joint."""
    lo, hi = max(1, round(0.07 * rate_hz)), max(1, round(0.2 * rate_hz))
    mean_len = 0.5 * (lo + hi)
    hit = np.zeros((T, fraction.shape[0]), dtype=bool)
    starts = rng.random((T, fraction.shape[0])) < fraction / mean_len
    for f, j in np.argwhere(starts):
        hit[f : f + int(rng.integers(lo, hi + 1)), j] = True
    return hit


def _exact_bursts(rng: np.random.Generator, T: int, fraction: np.ndarray, rate_hz: float) -> np.ndarray:
    """Returns (T, J) bool: non-overlapping bursts of 0.07-0.2 s covering `fraction` (J,) of each joint's frames
    (the burst count rounded at random), placed in random slots of the longest burst's length.

    Unlike _bursts (independent starts: a Poisson count, overlaps), the covered fraction is what was asked for in
    every recording, so a short session reproduces the paper's outlier-removal gain instead of scattering around
    a lower value (the gain is concave in the number of outliers).
    """
    lo, hi = max(1, round(0.07 * rate_hz)), max(1, round(0.2 * rate_hz))
    J = fraction.shape[0]
    slots = max(T // hi, 1)
    lengths = rng.integers(lo, hi + 1, size=(J, slots))
    hit = np.zeros((T, J), dtype=bool)
    for j in range(J):
        want = fraction[j] * T / (0.5 * (lo + hi))
        n = min(int(want) + int(rng.random() < want - int(want)), slots)
        for slot, length in zip(rng.permutation(slots)[:n], lengths[j, :n], strict=True):
            start = slot * hi + int(rng.integers(0, hi - length + 1))
            hit[start : start + length, j] = True
    return hit


_SEGMENT_OF_CHILD = {skeleton.INDEX[b]: i for i, (_, b) in enumerate(skeleton.SEGMENTS.values())}
BONE_SD_UNTABLED_M = 0.01  # length-error SD of the bones the tables do not cover (spine, neck, head, clavicles)


# Joints whose offset leans the way their parent's does (not towards their children): the knee and the ankle then err
# with the hip, and a straight leg stays straight, as Kinect legs do (UI-PRMD s01-s05, Kinect v2: standing knees read
# 1-6° bent; leaning towards the children, the simulated ones read 26-39°).
_KEEP_LINE = frozenset(skeleton.INDEX[n] for n in ("KNE_L", "KNE_R", "ANK_L", "ANK_R"))


def _side_hint(hint: np.ndarray | None, parent_off: np.ndarray, keep_line: bool) -> np.ndarray:
    """Returns (T, 3) the direction a child's offset leans to on its circle (see _propagate): its own hint, or its
    parent's offset direction where it has none or where keep_line."""
    return parent_off if hint is None or keep_line else hint


def _perpendicular_unit(e: np.ndarray, hint: np.ndarray) -> np.ndarray:
    """Returns (T, 3) unit vectors orthogonal to unit e (T, 3): hint (T, 3) made orthogonal, or any when parallel."""
    perp = hint - np.sum(hint * e, axis=-1, keepdims=True) * e
    n = np.linalg.norm(perp, axis=-1, keepdims=True)
    fallback = np.cross(e, np.where(np.abs(e[:, :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]))
    fallback /= np.linalg.norm(fallback, axis=-1, keepdims=True)
    return np.where(n > 1e-9, perp / np.where(n > 1e-9, n, 1.0), fallback)


def gaussian_offsets(
    pos: np.ndarray,
    mu: np.ndarray,
    sigma: np.ndarray,
    bone_mean: np.ndarray,
    bone_sd: np.ndarray,
    rng: np.random.Generator,
    dt: float,
) -> np.ndarray:
    """Returns the Gaussian-component offsets (T, J, 3), metres, camera frame, of a true pose sequence.

    pos: (T, J, 3) m, truth. mu, sigma: (J,) m, folded-normal parameters of each joint's offset distance.
    bone_mean, bone_sd: (14,) m, tabled segment-length error. The distance |offset_j(t)| = |mu_j + sigma_j z_j(t)|
    exactly (z: AR(1), 70 % shared by all joints). Its direction: ROOT's is fixed in the pelvis frame for the
    session (the candidate that best fits the segments); down the tree each child's measured position is put on
    the circle where its distance sphere meets the sphere of the wanted segment length (true length + bone_mean +
    bone_sd · AR(1)) around the measured parent, so every segment carries exactly its tabled error wherever the
    two spheres meet (see _propagate).
    """
    T, J = pos.shape[:2]
    own = ar1(rng, T, J, dt)
    for c in range(1, J):  # parents come first: each joint's own jitter follows its parent's (still unit variance)
        own[:, c] = JITTER_PARENT_CORR * own[:, skeleton.PARENT[c]] + np.sqrt(1.0 - JITTER_PARENT_CORR**2) * own[:, c]
    z = np.sqrt(JITTER_SHARED) * ar1(rng, T, 1, dt) + np.sqrt(1.0 - JITTER_SHARED) * own
    dist = np.abs(mu + sigma * z)  # (T, J)
    zeta = ar1(rng, T, len(skeleton.BONES), dt)  # (T, 19) length-error noise
    # The ROOT direction, fixed in the pelvis frame: the candidate (random directions and the six pelvis axes)
    # that best lets the segments carry their tabled length errors (judged on every 10th frame).
    R_world_pelvis = _pelvis_frames(pos)
    candidates = np.concatenate([_unit_vectors(rng, ROOT_CANDIDATES), np.eye(3), -np.eye(3)])
    sub = slice(None, None, 10)
    shortfall = [
        _propagate(pos[sub], dist[sub], zeta[sub], R_world_pelvis[sub] @ u, bone_mean, bone_sd)[1]
        for u in candidates
    ]  # fmt: skip
    best = candidates[int(np.argmin(shortfall))]
    off = _propagate(pos, dist, zeta, R_world_pelvis @ best, bone_mean, bone_sd)[0]
    delta, sd = _commanded_errors(pos, dist, zeta, off, bone_mean, bone_sd)
    return refine_offsets(pos, dist, off, skeleton.bone_lengths(pos) + delta + sd * zeta)


REFINE_SWEEPS = 25
UNTABLED_GAIN = 0.1  # the bones the tables do not cover (spine, neck, head, clavicles) give way more easily
CALIBRATION_ROUNDS = 6
CALIBRATION_STEP = 6  # calibrate on every 6th frame


def _commanded_errors(
    pos: np.ndarray, dist: np.ndarray, zeta: np.ndarray, off: np.ndarray, bone_mean: np.ndarray, bone_sd: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Returns (delta (19,), sd (19,)) m: the bone-length errors to aim at so that the achieved ones have the tabled
    mean and SD. Where the distance spheres cannot carry the tabled error, refine_offsets falls short by a roughly
    constant amount; a few rounds on a subsample of frames measure that shortfall and aim past it (bounded to 3
    tabled SDs)."""
    seg_bone = np.array([k for k, (_, c) in enumerate(skeleton.BONES) if c in _SEGMENT_OF_CHILD])
    seg_index = np.array([_SEGMENT_OF_CHILD[skeleton.BONES[k][1]] for k in seg_bone])
    target_mean, target_sd = bone_mean[seg_index], bone_sd[seg_index]
    delta = np.zeros(len(skeleton.BONES))
    sd = np.full(len(skeleton.BONES), BONE_SD_UNTABLED_M)
    delta[seg_bone], sd[seg_bone] = target_mean, target_sd
    sub = slice(None, None, CALIBRATION_STEP)
    p, d, z, o = pos[sub], dist[sub], zeta[sub], off[sub]
    true_len = skeleton.bone_lengths(p)
    for _ in range(CALIBRATION_ROUNDS):
        achieved = (
            skeleton.bone_lengths(p + refine_offsets(p, d, o, true_len + delta + sd * z))[:, seg_bone]
            - true_len[:, seg_bone]
        )
        step = np.clip(target_mean - achieved.mean(axis=0), -3 * target_sd, 3 * target_sd)
        delta[seg_bone] = np.clip(delta[seg_bone] + step, target_mean - 3 * target_sd, target_mean + 3 * target_sd)
        ratio = np.clip(target_sd / np.maximum(achieved.std(axis=0), 1e-9), 0.5, 1.5)
        sd[seg_bone] = np.clip(sd[seg_bone] * ratio, 0.0, 2.0 * target_sd)
    return delta, sd


def refine_offsets(
    pos: np.ndarray, dist: np.ndarray, off: np.ndarray, wanted: np.ndarray, *, compiled: bool = True
) -> np.ndarray:
    """Returns offsets (T, J, 3) m closer to the wanted bone lengths (T, 19) with |offset| = dist (T, J) exactly.

    Alternating projections (position-based-dynamics style), vectorised over frames: each sweep moves both ends of
    every bone towards its wanted length, then puts every joint back on its distance sphere around the truth.
    compiled: the sweeps in _kinect_noise_numba's kernel when numba is installed (the same offsets bit for bit as
    numpy's, compiled=False).
    """
    truth = np.ascontiguousarray(pos.transpose(1, 0, 2))  # (J, T, 3): one contiguous block per joint
    m = truth + off.transpose(1, 0, 2)
    wanted_by_bone = np.ascontiguousarray(wanted.T)  # (19, T)
    parents, children = skeleton.PARENT[1:], np.arange(1, skeleton.J)
    gain = [0.5 if c in _SEGMENT_OF_CHILD else UNTABLED_GAIN for c in children]
    if compiled and _kinect_noise_numba.AVAILABLE:
        radius_jt = np.ascontiguousarray(dist.T, dtype=np.float64)  # (J, T)
        _kinect_noise_numba.refine_sweeps(
            truth, m, radius_jt, wanted_by_bone, np.ascontiguousarray(parents, dtype=np.int64),
            children.astype(np.int64), np.array(gain), REFINE_SWEEPS,
        )  # fmt: skip
        return (m - truth).transpose(1, 0, 2)
    radius = dist.T[..., None]  # (J, T, 1)
    for _ in range(REFINE_SWEEPS):
        for k in range(len(skeleton.BONES)):
            p, c = parents[k], children[k]
            v = m[c] - m[p]
            n = np.maximum(np.sqrt(np.einsum("ti,ti->t", v, v)), 1e-12)
            corr = v * (gain[k] * (n - wanted_by_bone[k]) / n)[:, None]
            m[p] += corr
            m[c] -= corr
        r = m - truth
        rn = np.sqrt(np.einsum("jti,jti->jt", r, r))[..., None]
        m = truth + r * (radius / np.maximum(rn, 1e-12))
    return (m - truth).transpose(1, 0, 2)


ROOT_CANDIDATES = 16


def _pelvis_frames(pos: np.ndarray) -> np.ndarray:
    """Returns R_world_pelvis (T, 3, 3): columns = unit(HIP_L - HIP_R), the spine direction made orthogonal to it,
    and their cross product. pos: (T, J, 3) m, truth."""
    i = skeleton.INDEX
    x = pos[:, i["HIP_L"]] - pos[:, i["HIP_R"]]
    x /= np.linalg.norm(x, axis=-1, keepdims=True)
    y = _perpendicular_unit(x, pos[:, i["SPINE"]] - pos[:, i["ROOT"]])
    return np.stack([x, y, np.cross(x, y)], axis=-1)


def _child_hints(pos: np.ndarray, bone_mean: np.ndarray) -> dict[int, np.ndarray]:
    """Returns {joint: (T, 3)} the direction in which a joint's offset helps its tabled child segments: towards a
    child whose segment is tabled shorter, away from one tabled longer. Joints without such children are absent."""
    hints: dict[int, np.ndarray] = {}
    for p, c in skeleton.BONES:
        seg = _SEGMENT_OF_CHILD.get(c)
        if seg is None or bone_mean[seg] == 0.0:
            continue
        e = pos[:, c] - pos[:, p]
        e = e / np.maximum(np.linalg.norm(e, axis=-1, keepdims=True), 1e-12)  # a zero-length bone gives no hint
        hints[p] = hints.get(p, 0.0) - np.sign(bone_mean[seg]) * e
    return {j: h for j, h in hints.items() if np.all(np.linalg.norm(h, axis=-1) > 1e-6)}


def _propagate(
    pos: np.ndarray,
    dist: np.ndarray,
    zeta: np.ndarray,
    root_dir: np.ndarray,
    bone_mean: np.ndarray,
    bone_sd: np.ndarray,
) -> tuple[np.ndarray, float]:
    """Returns (offsets (T, J, 3) m, total length error that did not fit, m) for a ROOT direction (3,) or (T, 3).

    Down the tree, the measured child must lie on the sphere of radius dist_c around its true position (the
    distance law) and at the wanted length L + delta + sd·zeta from the measured parent: the two spheres meet in a
    circle, and the point of that circle nearest the child's hint direction (towards its own tabled-shorter
    children, away from tabled-longer ones; else the parent's offset direction) is taken. Where the spheres do not
    meet, the nearest feasible length is used and the gap is counted as shortfall.
    """
    T, J = dist.shape
    off = np.empty((T, J, 3))
    off[:, 0] = dist[:, :1] * np.broadcast_to(root_dir, (T, 3))
    hints = _child_hints(pos, bone_mean)
    shortfall = 0.0
    for k, (p, c) in enumerate(skeleton.BONES):
        bone = pos[:, c] - pos[:, p]
        length = np.linalg.norm(bone, axis=-1)
        seg = _SEGMENT_OF_CHILD.get(c)
        delta, sd = (bone_mean[seg], bone_sd[seg]) if seg is not None else (0.0, BONE_SD_UNTABLED_M)
        wanted = length + delta + sd * zeta[:, k]  # (T,) measured segment length, m
        w = bone - off[:, p]  # from the measured parent to the true child
        w_norm = np.maximum(np.linalg.norm(w, axis=-1), 1e-12)
        d = dist[:, c]
        reach = np.clip(wanted, np.abs(w_norm - d), w_norm + d)
        shortfall += float(np.sum(np.abs(wanted - reach)))
        along = np.clip((reach**2 - w_norm**2 - d**2) / (2.0 * w_norm), -d, d)  # component of off_c along w
        w_hat = w / w_norm[:, None]
        side = _perpendicular_unit(w_hat, _side_hint(hints.get(c), off[:, p], c in _KEEP_LINE))
        off[:, c] = along[:, None] * w_hat + np.sqrt(np.maximum(d**2 - along**2, 0.0))[:, None] * side
    return off, shortfall


def check_setting(device: str, view_deg: int, pose: str) -> None:
    """Raises SimulationError unless device, view and pose name a column of the tables."""
    if device not in DEVICES:
        raise SimulationError(f"unknown device {device!r}; the tables cover {', '.join(DEVICES)}")
    if view_deg not in VIEWS:
        raise SimulationError(f"view {view_deg!r} degrees is not tabled; use one of {', '.join(map(str, VIEWS))}")
    if pose not in POSES:
        raise SimulationError(f"unknown pose {pose!r}; use sitting or standing")


def add_kinect_noise(
    truth: Recording, *, device: str, view_deg: int, pose: str, rng: np.random.Generator
) -> tuple[Recording, np.ndarray]:
    """Returns (measured recording, outlier_mask (T, J) bool) for an exact `truth` recording.

    truth.positions: (T, J, 3) metres, camera frame, all finite. The mask is True exactly where a joint-frame was
    replaced by a tracking-loss outlier (outlier_law: a jump of random direction from the Kinect's biased estimate
    truth + offset, its length uniform over jump·[1 − h, 1 + h]); those frames keep state TRACKED, as the Kinect
    SDK often does. Inferred joint-frames get state 1, lost ones state 0 and NaN.
    """
    check_setting(device, view_deg, pose)
    pos = truth.positions
    if not np.all(np.isfinite(pos)):
        raise SimulationError("the truth recording must have every joint in every frame")
    T, J = pos.shape[:2]
    tables = load_tables()
    key = (device, pose, view_deg)
    mu, sigma = folded_normal_parameters(tables.offset_mean[key], tables.offset_sd[key])
    dt = float(np.median(np.diff(truth.t))) if T > 1 else 1.0 / 30.0
    rate = 1.0 / dt
    offsets = gaussian_offsets(pos, mu, sigma, tables.bone_mean[key], tables.bone_sd[key], rng, dt)
    measured = pos + offsets

    weights = loss_weights(device, view_deg)
    fraction, jump_m = setting_outlier_law(device, pose, view_deg)
    outliers = _exact_bursts(rng, T, fraction, rate)
    # The uniform component: a jump from the Kinect's own (biased) estimate, of length uniform over
    # jump·[1 − h, 1 + h], in a uniformly random direction, drawn anew every frame (outlier_law).
    radius = jump_m * (1.0 + OUTLIER_HALF_WIDTH * (2.0 * rng.random((T, J)) - 1.0))
    jump = measured + radius[..., None] * _unit_vectors(rng, T * J).reshape(T, J, 3)
    measured = np.where(outliers[..., None], jump, measured)

    lost = _bursts(rng, T, NOT_TRACKED_BASE * weights, rate) & ~outliers
    inferred = _bursts(rng, T, INFERRED_BASE * weights, rate) & ~outliers & ~lost
    extra = 1.5 * tables.offset_sd[key] * _unit_vectors(rng, J).T  # (3, J)
    measured = np.where(inferred[..., None], measured + extra.T, measured)
    measured[lost] = np.nan
    state = np.full((T, J), TRACKED, dtype=np.int8)
    state[inferred] = INFERRED
    state[lost] = NOT_TRACKED

    meta = dataclasses.replace(truth.meta, history=list(truth.meta.history), extra=dict(truth.meta.extra))
    meta.device, meta.view_deg, meta.pose = device, float(view_deg), pose
    meta.history.append(f"kinect_noise(device={device}, view={view_deg}, pose={pose})")
    meta.extra["noise_model"] = (
        "Wang et al. tables: folded-normal offset, AR(1) tau 0.2 s, tracking-loss jumps from the biased estimate "
        "calibrated on the gain table"
    )
    return Recording(truth.t.copy(), measured, state, meta), outliers


def offset_statistics(measured: Recording, truth: Recording, outlier_mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Returns (mean (J,), SD (J,)) of the Euclidean offset distance, metres, over TRACKED non-outlier frames."""
    d = np.linalg.norm(measured.positions - truth.positions, axis=-1)  # (T, J)
    keep = (measured.state == TRACKED) & ~outlier_mask
    d = np.where(keep, d, np.nan)
    return np.nanmean(d, axis=0), np.nanstd(d, axis=0)


def bone_length_error(measured: Recording, truth: Recording, outlier_mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Returns (mean (14,), SD (14,)) of measured - true segment length, metres, over frames whose ends are kept."""
    keep = (measured.state == TRACKED) & ~outlier_mask
    a, b = skeleton.SEGMENT_JOINTS[:, 0], skeleton.SEGMENT_JOINTS[:, 1]
    diff = measured.segment_lengths() - truth.segment_lengths()
    diff = np.where(keep[:, a] & keep[:, b], diff, np.nan)
    return np.nanmean(diff, axis=0), np.nanstd(diff, axis=0)
