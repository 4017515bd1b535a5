"""Reachable workspace: area and volume ratios of the hand path relative to the arm length."""

from __future__ import annotations

from typing import Any

import numpy as np

from kinect_agent.analysis.reachable import reachable_range
from kinect_agent.body.angles import body_frame
from kinect_agent.skeleton import INDEX
from kinect_agent.sources.simulator import simulate_truth


def _sweep_hand(rng: np.random.Generator, reach: float) -> np.ndarray:
    """A still body whose left hand visits random frontal directions at `reach` arm lengths, the elbow bent to fit."""
    base = simulate_truth("elbow_flexion", 1, seed=1).positions[:1]
    n = 20000
    p = np.repeat(base, n, axis=0)
    sho, elb, wri, han = (base[0, INDEX[j]] for j in ("SHO_L", "ELB_L", "WRI_L", "HAN_L"))
    l1, l2, l3 = np.linalg.norm(elb - sho), np.linalg.norm(wri - elb), np.linalg.norm(han - wri)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    forward = body_frame(base)[2][0]
    d *= np.where(d @ forward < 0, -1.0, 1.0)[:, None]  # the frontal hemisphere of the trunk frame
    dist = reach * (l1 + l2 + l3)
    a = (l1**2 - (l2 + l3) ** 2 + dist**2) / (2 * dist)  # elbow's offset along d (triangle l1, l2 + l3, dist)
    normal = np.cross(d, [0.0, 0.0, 1.0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    p_elb = sho + a * d + np.sqrt(np.maximum(l1**2 - a**2, 0.0)) * normal
    p_han = sho + dist * d
    p[:, INDEX["ELB_L"]] = p_elb
    p[:, INDEX["WRI_L"]] = p_elb + l2 / (l2 + l3) * (p_han - p_elb)
    p[:, INDEX["HAN_L"]] = p_han
    return p


def _side(positions: np.ndarray, side: str) -> dict[str, Any]:
    """Returns reachable_range's summary of one side, which these bodies always have."""
    found = reachable_range(positions)[side]
    assert found is not None, side
    return found


def test_hand_sweeping_the_whole_frontal_hemisphere_covers_it(rng: np.random.Generator) -> None:
    left = _side(_sweep_hand(rng, 1.0), "left")
    assert left["area_ratio"] > 0.97 and left["volume_ratio"] > 0.95
    assert all(q > 0.95 for q in left["quadrants"].values())


def test_reach_of_0_6_arm_lengths_gives_0_6_cubed_of_the_volume(rng: np.random.Generator) -> None:
    left = _side(_sweep_hand(rng, 0.6), "left")
    assert left["area_ratio"] > 0.97
    np.testing.assert_allclose(left["volume_ratio"], 0.6**3, atol=0.01)


def test_hand_close_to_the_shoulder_sweeps_nothing(rng: np.random.Generator) -> None:
    assert _side(_sweep_hand(rng, 0.4), "left")["area_ratio"] == 0.0


def test_arm_raised_sideways_reaches_the_lateral_quadrants_only() -> None:
    truth = simulate_truth("shoulder_abduction", 3, seed=1)
    right = _side(truth.positions, "right")
    q = right["quadrants"]
    assert q["upper_lateral"] > 0.05 and q["lower_lateral"] > 0.05
    assert q["upper_medial"] == 0 and q["lower_medial"] == 0
    assert 0 < right["area_ratio"] < 0.3
    np.testing.assert_allclose(right["arm_length_m"], 0.63, atol=0.1)


def test_untracked_arm_reads_none() -> None:
    p = simulate_truth("squat", 1, seed=1).positions.copy()
    p[:, INDEX["HAN_R"]] = np.nan
    assert reachable_range(p)["right"] is None
