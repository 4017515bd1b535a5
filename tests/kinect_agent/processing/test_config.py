"""The pipeline's settings: values out of range are refused naming the field; the settings cannot change once made."""

from __future__ import annotations

from typing import Any

import pytest
from pydantic import ValidationError

from kinect_agent.processing.config import SMOOTHERS, PipelineConfig

BAD = [
    ("smoother", {"smoother": "kalman"}),
    ("sigma_tracked_m", {"sigma_tracked_m": 0.0}),
    ("sigma_inferred_m", {"sigma_inferred_m": -0.01}),
    ("q_rot_rad", {"q_rot_rad": 0.0}),
    ("offline_q_rot_rad", {"offline_q_rot_rad": 0.0}),
    ("offline_q_root_m", {"offline_q_root_m": -1.0}),
    ("q_length_m", {"q_length_m": -0.001}),
    ("rate_ref_hz", {"rate_ref_hz": 0}),
    ("outlier_threshold", {"outlier_threshold": 1.0}),
    ("outlier_threshold", {"outlier_threshold": 0.0}),
    ("outlier_window_s", {"outlier_window_s": 0.0}),
    ("outlier_segment", {"outlier_segment": "sometimes"}),
    ("excursion_max_len_s", {"excursion_min_len_s": 2.0, "excursion_max_len_s": 1.0}),
    ("gate_chi2", {"gate_chi2": 0.0}),
    ("online_gate_chi2", {"online_gate_chi2": -3.0}),
    ("reacquire_s", {"reacquire_s": 0.0}),
    ("online_reacquire_s", {"online_reacquire_s": 0.0}),
    ("online_sigma_tracked_m", {"online_sigma_tracked_m": 0.0}),
    ("alpha", {"alpha": 0.0}),
    ("four_pass_combine", {"four_pass_combine": "mean"}),
    ("extra", {"extra": {}}),  # no such setting
]


@pytest.mark.parametrize(("field", "changes"), BAD, ids=[f"{f}={c}" for f, c in BAD])
def test_a_value_out_of_range_is_refused_naming_the_field(field: str, changes: dict[str, Any]) -> None:
    with pytest.raises(ValidationError) as refused:
        PipelineConfig(**changes)
    assert [e["loc"] for e in refused.value.errors()] == [(field,)]
    assert isinstance(refused.value, ValueError)  # callers catching ValueError keep working


def test_optional_settings_accept_none_and_the_limits_accept_values_inside() -> None:
    config = PipelineConfig(gate_chi2=None, reacquire_s=None, offline_q_rot_rad=None, q_length_m=0.0,
                            excursion_min_len_s=1.0, excursion_max_len_s=1.5, outlier_segment="or")  # fmt: skip
    assert config.gate_chi2 is None and config.q_length_m == 0.0 and config.outlier_segment == "or"
    assert set(SMOOTHERS) == {"urts", "four_pass"} and PipelineConfig().smoother in SMOOTHERS


def test_settings_are_frozen_and_variants_are_new_objects() -> None:
    config = PipelineConfig()
    with pytest.raises(ValidationError):
        config.smoother = "four_pass"  # type: ignore[misc]  # frozen: the assignment is refused, as tested
    variant = config.model_copy(update={"smoother": "four_pass"})
    assert variant.smoother == "four_pass" and config.smoother == "urts"
    assert PipelineConfig(**config.model_dump()) == config  # what a session file stores reads back the same
