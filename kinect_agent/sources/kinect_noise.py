"""Kinect measurement errors calibrated on the paper's accuracy tables (Wang et al., section 3.1).

What the tabled per-joint "mean" and "SD" mean here (and how tests compute the simulated statistic):
    d(t) = |measured(t) - truth(t)|, the Euclidean offset distance of one joint in one frame, metres;
    mean = mean of d over the frames of a session, SD = standard deviation of d over those frames,
    counting only frames whose state is TRACKED and that are not tracking-loss outliers (the frames the
    paper's mixture-model outlier removal keeps).

Model of the offset of joint j (the Gaussian component of the paper's mixture), see gaussian_offsets():
    |offset_j(t)| = |mu_j + sigma_j · z_j(t)|, z_j an AR(1) (discretised Ornstein-Uhlenbeck) process of unit
    variance with correlation time TAU_S, 70 % of its variance shared by all joints. That distance is a folded
    normal; mu_j and sigma_j are solved so its mean and SD equal the table (all tabled SD/mean ratios are below the
    folded normal's limit of 0.756). The direction: ROOT's is random and fixed for the session (the bias
    direction); each child's offset keeps its parent's component along the bone plus the segment's tabled length
    error, the rest of its length going perpendicular to the bone, so the distance law is untouched.
Tracking loss (the uniform component): bursts of a few frames in which a joint jumps to a uniformly random point
    in a box 0.25 m around the body; more frequent for distal joints, Kinect 1 and wider views. Inferred joints
    (state 1) carry an extra offset of 1.5 table SDs; not-tracked joints (state 0) are NaN.
Bone-length errors: steered towards the tabled mean (first order) with the tabled SD (AR(1) along the bone);
    second-order effects and frames where the joint's distance is too short to carry the length error leave the
    simulated segments somewhat longer than tabled. bone_length_error() computes the simulated statistic.
"""

from __future__ import annotations

import csv
import dataclasses
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
JITTER_SHARED = 0.7  # share of the jitter variance common to all joints (the whole skeleton wobbles together)
OUTLIER_BASE = 0.0015  # fraction of joint-frames replaced by tracking loss, for a proximal joint, Kinect 2, 0°
INFERRED_BASE = 0.006  # fraction of joint-frames flagged inferred, same scaling
NOT_TRACKED_BASE = 0.0015  # fraction of joint-frames lost (NaN), same scaling
BOX_MARGIN_M = 0.25


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


def _per_item(path: Path, key: str, names: tuple[str, ...]) -> tuple[dict, dict]:
    rows = {r[key]: r for r in _read_rows(path)}
    missing = [n for n in names if n not in rows]
    if missing:
        raise SimulationError(f"{path}: rows missing for {', '.join(missing)}")
    mean, sd = {}, {}
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


def _bursts(rng: np.random.Generator, T: int, fraction: np.ndarray, rate_hz: float) -> np.ndarray:
    """Returns (T, J) bool: bursts of 0.07-0.2 s covering about `fraction` (J,) of the frames of each joint."""
    lo, hi = max(1, round(0.07 * rate_hz)), max(1, round(0.2 * rate_hz))
    mean_len = 0.5 * (lo + hi)
    hit = np.zeros((T, fraction.shape[0]), dtype=bool)
    starts = rng.random((T, fraction.shape[0])) < fraction / mean_len
    for f, j in np.argwhere(starts):
        hit[f : f + int(rng.integers(lo, hi + 1)), j] = True
    return hit


_SEGMENT_OF_CHILD = {skeleton.INDEX[b]: i for i, (_, b) in enumerate(skeleton.SEGMENTS.values())}
BONE_SD_UNTABLED_M = 0.01  # length-error SD of the bones the tables do not cover (spine, neck, head, clavicles)


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
    exactly (z: AR(1), 70 % shared by all joints). Its direction: ROOT's is a random unit vector fixed for the
    session; down the tree, each child's offset has the parent's component along the bone plus the segment's
    length error (bone_mean + bone_sd · AR(1)), and the rest of its length perpendicular to the bone, on the
    parent's side, so segments come out longer/shorter by the tabled amount wherever the distance allows it.
    """
    T, J = pos.shape[:2]
    z = np.sqrt(JITTER_SHARED) * ar1(rng, T, 1, dt) + np.sqrt(1.0 - JITTER_SHARED) * ar1(rng, T, J, dt)
    dist = np.abs(mu + sigma * z)  # (T, J)
    zeta = ar1(rng, T, len(skeleton.BONES), dt)  # (T, 19) length-error noise
    # The ROOT direction: the one of ROOT_CANDIDATES random directions that best lets the segments carry their
    # tabled length errors (judged on every 10th frame).
    candidates = _unit_vectors(rng, ROOT_CANDIDATES)
    sub = slice(None, None, 10)
    shortfall = [
        _propagate(pos[sub], dist[sub], zeta[sub], u, bone_mean, bone_sd)[1] for u in candidates
    ]  # fmt: skip
    return _propagate(pos, dist, zeta, candidates[int(np.argmin(shortfall))], bone_mean, bone_sd)[0]


ROOT_CANDIDATES = 16


def _propagate(
    pos: np.ndarray,
    dist: np.ndarray,
    zeta: np.ndarray,
    root_dir: np.ndarray,
    bone_mean: np.ndarray,
    bone_sd: np.ndarray,
) -> tuple[np.ndarray, float]:
    """Returns (offsets (T, J, 3) m, total length error that did not fit, m) for one ROOT direction (3,)."""
    T, J = dist.shape
    off = np.empty((T, J, 3))
    off[:, 0] = dist[:, :1] * root_dir
    shortfall = 0.0
    for k, (p, c) in enumerate(skeleton.BONES):
        e = pos[:, c] - pos[:, p]
        e /= np.linalg.norm(e, axis=-1, keepdims=True)
        seg = _SEGMENT_OF_CHILD.get(c)
        delta, sd = (bone_mean[seg], bone_sd[seg]) if seg is not None else (0.0, BONE_SD_UNTABLED_M)
        wanted = np.sum(off[:, p] * e, axis=-1) + delta + sd * zeta[:, k]
        along = np.clip(wanted, -dist[:, c], dist[:, c])
        shortfall += float(np.sum(np.abs(wanted - along)))
        side = _perpendicular_unit(e, off[:, p])
        off[:, c] = along[:, None] * e + np.sqrt(np.maximum(dist[:, c] ** 2 - along**2, 0.0))[:, None] * side
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
    replaced by a tracking-loss outlier (uniform in the body box); those frames keep state TRACKED, as the Kinect
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
    outliers = _bursts(rng, T, OUTLIER_BASE * weights, rate)
    lo = np.nanmin(pos, axis=1) - BOX_MARGIN_M  # (T, 3) body box per frame
    hi = np.nanmax(pos, axis=1) + BOX_MARGIN_M
    uniform = lo[:, None, :] + rng.random((T, J, 3)) * (hi - lo)[:, None, :]
    measured = np.where(outliers[..., None], uniform, measured)

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
    meta.extra["noise_model"] = "Wang et al. tables: folded-normal offset, AR(1) tau 0.2 s, uniform bursts"
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
