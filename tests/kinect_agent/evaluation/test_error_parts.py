"""kinect_agent/evaluation/error_parts.py: the body-frame bias/random split of joint-position errors, on real
mocap motion."""

from pathlib import Path

import numpy as np
import pytest

from kinect_agent.evaluation.error_parts import ErrorSums, body_rotations, error_sums
from kinect_agent.formats import amc
from kinect_agent.sources.mocap_truth import resample

ARM_CIRCLES = "hdm05/rotateArmsBothBackward1Reps/HDM_bd_rotateArmsBothBackward1Reps_001_120.amc"


def _rms_mm(sums: ErrorSums) -> dict[str, float]:
    """Returns the sums' RMS parts in mm, each defined (these errors are never empty)."""
    parts = sums.rms_mm()
    defined = {name: value for name, value in parts.items() if value is not None}
    assert defined.keys() == parts.keys(), parts
    return defined


@pytest.fixture
def truth(data_dir: Path) -> np.ndarray:
    """(T, J, 3) m: an HDM05 arm-circle clip at 30 Hz (the trunk turns and sways while the arms circle)."""
    return resample(amc.read(data_dir / ARM_CIRCLES), 30.0)[1]


@pytest.mark.shared_data
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_an_offset_fixed_in_the_body_frame_is_all_bias(truth: np.ndarray, seed: int) -> None:
    offsets = np.random.default_rng(seed).normal(0.0, 0.05, size=(truth.shape[1], 3))  # (J, 3) m, body frame
    R = body_rotations(truth)  # camera -> body
    estimate = truth + np.einsum("tba,jb->tja", R, offsets)  # the same body-frame offset in every frame
    parts = _rms_mm(error_sums(estimate, truth))
    np.testing.assert_allclose(parts["random_mm"], 0.0, atol=1e-6, err_msg=f"seed {seed}")
    expected = 1e3 * np.sqrt(np.mean(np.sum(offsets**2, axis=-1)))
    np.testing.assert_allclose([parts["bias_mm"], parts["rmse_mm"]], expected, rtol=1e-9, err_msg=f"seed {seed}")


@pytest.mark.shared_data
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_parts_add_up_and_white_noise_is_random(truth: np.ndarray, seed: int) -> None:
    rng = np.random.default_rng(seed)
    camera_offset = rng.normal(0.0, 0.05, size=(truth.shape[1], 3))  # fixed in the camera frame: not body bias
    estimate = truth + camera_offset + rng.normal(0.0, 0.02, size=truth.shape)
    s = error_sums(estimate, truth)
    np.testing.assert_allclose(s.random + s.bias, s.total, rtol=1e-12, err_msg=f"seed {seed}")
    parts = _rms_mm(error_sums(truth + rng.normal(0.0, 0.02, size=truth.shape), truth))
    assert parts["bias_mm"] < 0.25 * parts["random_mm"], f"seed {seed}: white noise is random, {parts}"
    np.testing.assert_allclose(parts["rmse_mm"], 20.0 * np.sqrt(3), rtol=0.1, err_msg=f"seed {seed}")


def test_shapes_are_checked() -> None:
    with pytest.raises(ValueError, match=r"\(T, J, 3\)"):
        error_sums(np.zeros((4, 20, 3)), np.zeros((4, 19, 3)))
