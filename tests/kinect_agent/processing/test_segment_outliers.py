"""Segment-length-deviation outliers: sustained tracking loss that a temporal residual cannot see."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from kinect_agent import skeleton
from kinect_agent.evaluation.pairs import well_estimated
from kinect_agent.processing.combined_outliers import remove_outliers_combined
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.segment_outliers import segment_outlier_probabilities
from kinect_agent.recording import Recording

# A standing pose, m (x side, y up, z depth), one row per joint in skeleton.JOINTS order.
POSE = np.array([
    [0.0, 1.0, 2.5], [0.0, 1.25, 2.5], [0.0, 1.5, 2.5], [0.0, 1.7, 2.5],
    [-0.18, 1.45, 2.5], [-0.2, 1.17, 2.5], [-0.21, 0.92, 2.45], [-0.21, 0.84, 2.43],
    [0.18, 1.45, 2.5], [0.2, 1.17, 2.5], [0.21, 0.92, 2.45], [0.21, 0.84, 2.43],
    [-0.1, 0.95, 2.5], [-0.1, 0.5, 2.5], [-0.1, 0.08, 2.5], [-0.1, 0.02, 2.4],
    [0.1, 0.95, 2.5], [0.1, 0.5, 2.5], [0.1, 0.08, 2.5], [0.1, 0.02, 2.4],
])  # fmt: skip


def _wrist_plateau(rng: np.random.Generator) -> tuple[Recording, np.ndarray]:
    """10 s at 30 Hz, body swaying, 10 mm noise; WRI_R held 0.5 m off for 1.2 s (> the 0.5 s temporal window), the
    hand following it as on real Kinect failures. Returns (recording, truth (T, J) bool: WRI_R and HAN_R off)."""
    T = 300
    t = np.arange(T) / 30.0
    sway = 0.1 * np.sin(2 * np.pi * 0.3 * t)[:, None, None] * np.array([1.0, 0.0, 0.3])
    positions = POSE[None] + sway + rng.normal(0.0, 0.01, (T, skeleton.J, 3))
    truth = np.zeros((T, skeleton.J), bool)
    frames = slice(120, 156)
    for name in ("WRI_R", "HAN_R"):
        positions[frames, skeleton.INDEX[name]] += np.array([0.3, 0.4, 0.0])
        truth[frames, skeleton.INDEX[name]] = True
    return Recording.from_positions(t, positions), truth


def test_sustained_wrist_loss_is_flagged_and_clean_frames_are_not(rng: np.random.Generator) -> None:
    rec, truth = _wrist_plateau(rng)
    config = PipelineConfig(outlier_segment="max")
    flags = segment_outlier_probabilities(rec, config) > config.outlier_threshold
    wrist = truth[:, skeleton.INDEX["WRI_R"]]
    recall = (flags[:, skeleton.INDEX["WRI_R"]] & wrist).sum() / wrist.sum()  # a hand moved with it keeps its length
    precision = (flags & truth).sum() / max(flags.sum(), 1)
    np.testing.assert_array_less(0.9, [recall, precision], err_msg=f"recall {recall:.2f}, precision {precision:.2f}")
    _, prob = remove_outliers_combined(rec, config)
    combined = prob > config.outlier_threshold
    assert (combined & truth).sum() >= 0.9 * wrist.sum(), "the combined probability lost the segment evidence"


def test_flagged_joint_frames_of_real_pair_are_farther_from_vicon(data_dir: Path) -> None:
    from bench import real_pairs as rp

    kinect_path = next((p for p in rp.pair_paths() if "-ELK-" in p.name), None)
    assert kinect_path is not None, f"no KERAAL ELK pair under {data_dir}"
    kinect, vicon = rp.read_pair(kinect_path)
    good = well_estimated(vicon.meta.extra.get("fallback_joints", []))
    truth = rp.registered_truth(kinect, vicon, rp.align(kinect, vicon, good))
    offset = np.linalg.norm(kinect.positions - truth, axis=-1)[:, good]  # (T, G) m
    flags = (segment_outlier_probabilities(kinect, PipelineConfig()) > 0.95)[:, good]
    ok = np.isfinite(offset)
    assert (flags & ok).sum() >= 10, "the ELK wrist plateau was not flagged"
    flagged, unflagged = np.median(offset[flags & ok]), np.median(offset[~flags & ok])
    assert flagged > 2.0 * unflagged, f"flagged {flagged * 1000:.0f} mm vs unflagged {unflagged * 1000:.0f} mm"
