"""Outlier probability from segment-length deviation (Wang et al., section 3.2, with a non-temporal residual).

The temporal residual of kinect_agent.processing.outliers judges a joint against its own 0.5 s neighbourhood, so a
tracking failure that holds a joint off for longer than the window looks smooth and passes. Bones have constant
length, so a joint that sits in the wrong place stretches or shrinks the bones that touch it for as long as the
failure lasts:

    d[t, b] = L_b(t) − median_t L_b          signed deviation of bone b = (parent p, child c) from the recording's
                                             robust length, metres (skeleton.BONES, all 19 bones)

Attribution. A deviating bone has two ends; the culprit is the end whose *other* bones deviate too (a joint whose
both adjacent bones are off is the one misplaced; the neighbour that shares one bad bone with it has its other bones
intact). With z[t, b] = |d[t, b]| / s_b (s_b the bone's robust SD, 1.4826·MAD, floored at config.outlier_min_sigma_m)
and a_k(b) = (max over the other bones b' of joint k of z[t, b'] / Z_OTHER)² (unclipped, so the end with the worse
other bones wins), the end k ∈ {p, c} gets the share, with π = DISTAL_PRIOR,

    share_c = (a_c + π) / (a_c + a_p + π),     share_p = a_p / (a_c + a_p + π)

so an isolated bad bone (neither end's other bones off, e.g. a wrist whose hand follows it) goes to the distal end:
tracking loss hits the extremities, and the proximal joint is held by its other bones. The joint's residual is the
attributed deviation of largest magnitude among its bones, e[t, j] = share·d (signed, metres), and the same
Gaussian + uniform mixture as the temporal residual (outliers.fit_mixture, per joint, the same floors and SDK-state
classes) gives P(uniform | e). A limb moved rigidly (e.g. wrist and hand together) keeps the hand's bone length, so
the hand is not found here; the temporal residual and the UKF's gate remain for it.

Combination with the temporal probability (combined_outliers.py, PipelineConfig.outlier_segment): "max" or "or";
off by default (None): it gains on real pairs but lowers precision on simulated loss (why: bench/README.md, "Real
Kinect against Vicon", segment-length residual).
"""

from __future__ import annotations

import warnings

import numpy as np

from kinect_agent import skeleton
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.outliers import fit_mixture
from kinect_agent.recording import Recording
from kinect_agent.skeleton import INFERRED, NOT_TRACKED

Z_OTHER = 4.0  # robust z of a joint's other bones at which that end takes full blame
DISTAL_PRIOR = 0.25  # blame the distal end gets when neither end's other bones deviate

_PARENTS = np.array([p for p, _ in skeleton.BONES])  # (B,)
_CHILDREN = np.array([c for _, c in skeleton.BONES])  # (B,)
_B = len(skeleton.BONES)
# INCIDENT[j, b]: bone b touches joint j.
INCIDENT = np.zeros((skeleton.J, _B), dtype=bool)
INCIDENT[_PARENTS, np.arange(_B)] = True
INCIDENT[_CHILDREN, np.arange(_B)] = True


def bone_deviation(positions: np.ndarray, min_sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """Returns (d (T, B) m, z (T, B)): each bone's signed deviation from its median length and its robust z-score.

    positions: (T, J, 3) m, NaN = untracked. B = len(skeleton.BONES); NaN where an end is untracked.
    """
    L = skeleton.bone_lengths(positions)  # (T, B)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN bones
        d = L - np.nanmedian(L, axis=0)
        s = np.maximum(np.nan_to_num(1.4826 * np.nanmedian(np.abs(d), axis=0), nan=min_sigma), min_sigma)
    return d, np.abs(d) / s


def _other_max(z: np.ndarray, joint: np.ndarray) -> np.ndarray:
    """Returns (T, B): for each bone b, the largest z of the *other* bones at joint[b] (0 when there are none)."""
    zz = np.nan_to_num(z)  # (T, B)
    mask = INCIDENT[joint] & ~np.eye(_B, dtype=bool)  # (B, B'): other bones at that end of b
    return np.max(np.where(mask[None], zz[:, None, :], 0.0), axis=-1)


def attributed_residual(positions: np.ndarray, min_sigma: float) -> np.ndarray:
    """Returns e (T, J) m: each joint's attributed bone-length deviation of largest magnitude (signed); NaN when no
    bone of the joint has both ends tracked.

    positions: (T, J, 3) m, NaN = untracked.
    """
    d, z = bone_deviation(positions, min_sigma)
    a_p = (_other_max(z, _PARENTS) / Z_OTHER) ** 2
    a_c = (_other_max(z, _CHILDREN) / Z_OTHER) ** 2
    prior = DISTAL_PRIOR
    den = a_p + a_c + prior
    contrib = np.full((positions.shape[0], skeleton.J, _B), np.nan)  # (T, J, B)
    idx = np.arange(_B)
    contrib[:, _PARENTS, idx] = a_p / den * d
    contrib[:, _CHILDREN, idx] = (a_c + prior) / den * d
    mag = np.where(np.isfinite(contrib), np.abs(contrib), -1.0)
    best = np.argmax(mag, axis=-1)  # (T, J)
    e = np.take_along_axis(contrib, best[..., None], axis=-1)[..., 0]
    return e


def segment_outlier_probabilities(rec: Recording, config: PipelineConfig | None = None) -> np.ndarray:
    """Returns (T, J) in [0, 1]: P(tracking loss) of each joint-frame from its attributed segment-length deviation.

    A per-joint Gaussian + uniform mixture (outliers.fit_mixture, σ ≥ config.outlier_min_sigma_m, uniform range ≥
    config.outlier_min_range_m, Gaussian weights ≥ 0.5, tracked / inferred classes) fitted by EM to
    attributed_residual(); 0 where the residual is undefined, 1 where the joint is not tracked.
    """
    config = config or PipelineConfig()
    if rec.n_frames == 0:
        return np.zeros((0, rec.positions.shape[1]))
    positions = np.where((rec.state != NOT_TRACKED)[..., None], rec.positions, np.nan)
    e = attributed_residual(positions, config.outlier_min_sigma_m)
    cls = (rec.state == INFERRED).astype(int)
    mix = fit_mixture(e, cls, n_classes=2, rho0=0.95, min_sigma=config.outlier_min_sigma_m,
                      min_width=config.outlier_min_range_m, min_rho=0.5)  # fmt: skip
    prob = np.nan_to_num(mix.posterior_uniform(e, cls), nan=0.0)
    prob = np.where(rec.state == NOT_TRACKED, 1.0, prob)
    return np.clip(prob, 0.0, 1.0)
