"""Fast, large arm motion (issue 13): the offline pipeline against the CV Kalman + RTS smoother on arm circles."""

from pathlib import Path

import numpy as np
import pytest

from bench import arms
from kinect_agent.processing.config import PipelineConfig


@pytest.mark.parametrize("seed", [1, 2, 3])  # never one seed: a gain that holds on one draw only is no gain
@pytest.mark.parametrize("view", [0, 60])
@pytest.mark.parametrize("motion", ["rotateArms", "cmu_ArmCircle"])
def test_offline_beats_cv_kalman_rts_on_arm_circles(data_dir: Path, motion: str, view: int, seed: int) -> None:
    """HDM05 rotateArmsBothBackward (subject bk's 4 clips pooled, 1 s each) and CMU 13_29's arm circles (6 s) seen
    by a simulated Kinect 2: the offline pipeline must be closer to the truth than CV Kalman + RTS, pooled over the
    clips. Measured 2026-11-25 (bench/README.md, "Fast arm motion"): rotateArms 101-124 vs 113-134 mm, arm circles
    93-118 vs 108-133 mm."""
    assert arms.DATA_DIR.resolve() == data_dir.resolve(), f"bench/arms.py reads {arms.DATA_DIR}, tests {data_dir}"
    clips = [c for c in arms.truths([motion], clips=4) if c.name.startswith("HDM_bk") or motion.startswith("cmu")]
    assert clips, f"no {motion} truth in {data_dir}"
    config = PipelineConfig()
    sq = {"pipeline": 0.0, "cv_kalman_rts": 0.0}
    n = 0
    for k, clip in enumerate(clips):
        measured, truth, _ = arms.measure(clip, k, view, seed)
        for method in sq:
            est, _ = arms.estimate(method, measured, config)
            sq[method] += float(np.sum((est - truth) ** 2))
        n += truth.shape[0] * truth.shape[1]
    pipeline, cv = (1e3 * np.sqrt(sq[m] / n) for m in ("pipeline", "cv_kalman_rts"))
    assert pipeline < cv, f"{motion} at {view}°, seed {seed}: pipeline {pipeline:.1f} mm vs CV {cv:.1f} mm"


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("view", [0, 60])
def test_no_arm_circle_clip_is_thrown_off(data_dir: Path, view: int, seed: int) -> None:
    """Every rotateArms clip of `bench/arms.py --clips 2` (2 per subject), one by one: the pipeline within 1.5 × CV
    Kalman + RTS. Before ROOT's rotation was excluded from re-acquisition, clip 005 at 0°, seed 2 came out at 258 mm
    (CV 91): a hip gated for 0.1 s restarted the whole body's orientation from one frame's inverse kinematics, which
    had it flipped, and the arms went 1.3 m off; now 80 mm."""
    assert arms.DATA_DIR.resolve() == data_dir.resolve(), f"bench/arms.py reads {arms.DATA_DIR}, tests {data_dir}"
    config = PipelineConfig()
    for k, clip in enumerate(arms.truths(["rotateArms"], clips=2)):
        measured, truth, _ = arms.measure(clip, k, view, seed)
        rmse = {}
        for method in ("pipeline", "cv_kalman_rts"):
            est, _ = arms.estimate(method, measured, config)
            rmse[method] = 1e3 * float(np.sqrt(np.mean(np.sum((est - truth) ** 2, axis=-1))))
        assert rmse["pipeline"] < 1.5 * rmse["cv_kalman_rts"], f"{clip.name} at {view}°, seed {seed}: {rmse}"


@pytest.mark.parametrize("view", [0, 60])
def test_exact_input_error_is_the_unscented_mean(data_dir: Path, view: int) -> None:
    """Fed the exact truth (0.1 mm white noise), the default pipeline ends about 28 mm off on CMU arm circles because
    the UKF takes z − Σ Wm·h(σ) as innovation: with joint-angle spreads of 10-17° the sigma points' mean of the
    chain's positions lies inside h(x̄) (a curved chain pulls its ends in), so the filter settles on a state whose own
    joints overshoot the data, and passes 1-2 lengthen the bones by 4-21 mm. Centring the innovation on the mean
    state's joints (innovation_at_mean) removes that: about 9 mm (bench/README.md, "Fast arm motion"). Exact input
    does not depend on the seed. The exact-input settings (test_exact_input.py) are off here: this holds the diagnosis
    of the filter's own innovation."""
    clip = arms.truths(["cmu_ArmCircle"], clips=1)[0]
    measured, truth, _ = arms.measure(clip, 0, view, 1, white_m=1e-4)
    rmse = {}
    for at_mean in (False, True):
        config = PipelineConfig(innovation_at_mean=at_mean, rigid_input_sd_m=None)  # not as an exact input
        est, _ = arms.estimate("pipeline", measured, config)
        rmse[at_mean] = 1e3 * float(np.sqrt(np.mean(np.sum((est - truth) ** 2, axis=-1))))
    assert rmse[True] < 12.0 and rmse[False] > 2.0 * rmse[True], f"view {view}°: {rmse}"
