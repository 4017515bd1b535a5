"""The sagittal planar angles (shoulder and hip flexion) keep one side of their seam where real limbs go, so a session's
range of motion and curve do not wrap (kinect_agent.body.angles: SAGITTAL_SEAM_DEG; bench/flexion_seam.py and
bench/README.md, "Shoulder and hip flexion at their seam").

In the trunk's frame a limb can pass 180°: the arms held overhead while the trunk leans forward 20-40° (UI-PRMD deep
squat on the Kinect: shoulder flexion 170-250°), the Kinect's thighs in a sit-to-stand or flipped over the top at a
hurdle step's knee lift (hip flexion up to 250°). Before (the seam at −120°, that is 240°): those curves crossed it and
the ranges of motion the server stored read −118..239° (about 357°, a whole turn) for all three recordings below."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent.analysis.angles import measured_angles
from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.analysis.report import analyze_recording
from kinect_agent.body.angles import DOMAIN_DEG, SAGITTAL_SEAM_DEG, body_frame, joint_angles
from kinect_agent.formats import ui_prmd
from kinect_agent.skeleton import INDEX
from kinect_agent.sources.simulator import simulate_truth
from tests.conftest import DATA

FOLDERS = {"correct": "Segmented Movements", "incorrect": "Incorrect Segmented Movements"}
# (kind, movement, subject, exercise, angle, before: the stored range's (min, max) with the seam at −120°, whether
# the measured curve stays on one side of the seam: not at the hurdle step, whose mistracked thigh flips over the top
# to 259-260°, as far as the seam; its range's percentiles keep one side)
CASES = [
    ("correct", "m01", "s02", "deep_squat", "shoulder_flexion_R", (-118.4, 239.2), True),
    ("incorrect", "m05", "s01", "sit_to_stand", "hip_flexion_L", (-118.7, 238.5), True),
    ("correct", "m02", "s04", "hurdle_step", "hip_flexion_R", (-118.4, 236.5), False),
]
WHOLE_TURN_DEG = 300.0  # a range this wide is the curve crossing its seam, not a movement


@pytest.mark.parametrize(("kind", "movement", "subject", "slug", "angle", "before", "curve_too"), CASES)
def test_uiprmd_flexion_range_does_not_cross_the_seam(
    kind: str, movement: str, subject: str, slug: str, angle: str, before: tuple[float, float], curve_too: bool
) -> None:
    folder = DATA / "ui-prmd" / FOLDERS[kind] / "Kinect"
    if not folder.is_dir():
        pytest.skip(f"{folder} not available")
    rec = ui_prmd.read_episodes(folder, movement=movement, subject=subject)
    rom = analyze_recording(rec, EXERCISES[slug]).range_of_motion[angle]
    assert rom.range_deg is not None and rom.range_deg < WHOLE_TURN_DEG, (
        f"{movement} {subject} {kind} {angle}: range {rom.min_deg}..{rom.max_deg} (before {before}) crosses the seam"
    )
    if curve_too:  # the session page's curve: the measured angle
        curve = measured_angles(rec.t, rec.positions).angles[angle]
        defined = curve[np.isfinite(curve)]
        assert np.max(np.abs(np.diff(defined))) < 180.0, f"{angle}: the curve jumps across its seam"


def test_arms_overhead_with_the_trunk_leaning_forward_read_past_180_without_wrapping() -> None:
    """Arms straight up while the trunk leans forward 0-70° about its left-right axis: shoulder flexion 180-250°, one
    continuous curve (before: past 240° it read −120° and less)."""
    still = simulate_truth("squat", 1, seed=0).positions[0]
    up, left, forward = (v[0] for v in body_frame(still[None]))
    lean = np.radians(np.linspace(0.0, 70.0, 71))[:, None]
    up_leaning, forward_leaning = np.cos(lean) * up + np.sin(lean) * forward, np.cos(lean) * forward - np.sin(lean) * up
    root = still[INDEX["ROOT"]]
    positions = np.repeat(still[None], lean.size, axis=0)
    for joint in ("SPINE", "NECK", "HEAD", "SHO_L", "SHO_R"):
        d = still[INDEX[joint]] - root
        positions[:, INDEX[joint]] = root + (d @ up) * up_leaning + (d @ left) * left + (d @ forward) * forward_leaning
    for side in "LR":
        for joint, reach_m in (("ELB", 0.3), ("WRI", 0.55), ("HAN", 0.62)):
            positions[:, INDEX[f"{joint}_{side}"]] = positions[:, INDEX[f"SHO_{side}"]] + reach_m * up
    flexion = joint_angles(positions)["shoulder_flexion_L"]
    lo, hi = DOMAIN_DEG["shoulder_flexion_L"]
    assert lo == SAGITTAL_SEAM_DEG and np.all((flexion >= lo) & (flexion < hi))
    np.testing.assert_allclose(flexion, 180.0 + np.degrees(lean[:, 0]), atol=1e-6, err_msg="arms up, trunk leaning")
