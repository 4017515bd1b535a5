"""The segment-length bias step (length_bias.py): its own switch, the bones it scales, offline and online, and
the inputs and devices it must leave alone (issue 24 point 3)."""

from __future__ import annotations

import numpy as np
import pydantic
import pytest

from kinect_agent import skeleton
from kinect_agent.processing import length_bias
from kinect_agent.processing.config import PipelineConfig, config_for_device
from kinect_agent.processing.pipeline import process
from kinect_agent.recording import Recording
from tests.kinect_agent.processing._data import smooth_motion

RATIOS = {"ARM_UP_L": 1.1, "ARM_LO_R": 0.95}


def _bone(segment: str) -> str:
    return "-".join(skeleton.SEGMENTS[segment])


def _recording(t: np.ndarray, positions: np.ndarray) -> Recording:
    return Recording(t, positions, np.full(positions.shape[:2], skeleton.TRACKED, dtype=np.int8))


def _noisy(seed: int, sd_m: float = 0.01) -> Recording:
    rng = np.random.default_rng(seed)
    t, positions, _ = smooth_motion(60, rng)
    return _recording(t, positions + rng.normal(0.0, sd_m, positions.shape))


def test_bone_ratios_scale_exactly_the_named_segments() -> None:
    ratios = length_bias.bone_ratios(RATIOS)
    expected = np.ones(len(skeleton.BONES))
    for segment, ratio in RATIOS.items():
        a, b = skeleton.SEGMENTS[segment]
        expected[skeleton.BONES.index((skeleton.INDEX[a], skeleton.INDEX[b]))] = ratio
    np.testing.assert_array_equal(ratios, expected)
    assert length_bias.apply(np.full(len(skeleton.BONES), 0.3), None).tolist() == [0.3] * len(skeleton.BONES)


@pytest.mark.parametrize("table", [{"ELBOW": 1.1}, {"ARM_UP_L": 2.5}, {"ARM_UP_L": 0.4}])
def test_the_config_refuses_unknown_segments_and_implausible_factors(table: dict[str, float]) -> None:
    with pytest.raises(pydantic.ValidationError):
        PipelineConfig(length_bias=table)


@pytest.mark.parametrize("online", [False, True])
def test_the_fixed_lengths_are_the_estimates_times_the_factors(online: bool) -> None:
    """The step changes the lengths the filter fixes by exactly its factors and no other bone: the passes before it
    are the same with the switch on or off."""
    rec = _noisy(3)
    off = process(rec, online=online).quality["segment_lengths_m"]
    on = process(rec, online=online, config=PipelineConfig(length_bias=RATIOS)).quality["segment_lengths_m"]
    scaled = {_bone(s): r for s, r in RATIOS.items()}
    for bone, length in off.items():
        assert on[bone] == pytest.approx(scaled.get(bone, 1.0) * length, rel=1e-12)


def test_an_exact_input_is_not_scaled() -> None:
    """Mocap or a filtered recording fed again (the exact-input settings) has the body's own bones: no device bias."""
    rng = np.random.default_rng(5)
    t, positions, _ = smooth_motion(60, rng)
    rec = _recording(t, positions + rng.normal(0.0, 1e-4, positions.shape))
    off = process(rec).quality
    on = process(rec, config=PipelineConfig(length_bias=RATIOS)).quality
    assert on["rigid_input"] and on["segment_lengths_m"] == off["segment_lengths_m"]


def test_no_device_gets_another_devices_factors() -> None:
    """The webcam's landmarks are not a Kinect's joints: it never gets the Kinect 2 table (nor does any device
    without a table of its own)."""
    assert config_for_device("webcam").length_bias is None
    assert config_for_device("kinect1").length_bias is None
    assert set(length_bias.RATIOS) <= {"kinect2"}
