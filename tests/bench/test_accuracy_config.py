"""bench/accuracy.py --set: PipelineConfig overrides are typed and checked."""

import pytest

from bench.accuracy import pipeline_config


def test_overrides_are_typed() -> None:
    config = pipeline_config(["outlier_window_s=0.5", "outlier_iterations=3", "gate_chi2=None", "smoother=four_pass"])
    assert (config.outlier_window_s, config.outlier_iterations, config.gate_chi2) == (0.5, 3, None)
    assert config.smoother == "four_pass"
    config = pipeline_config(["outlier_segment=max", "outlier_excursions=false"])
    assert (config.outlier_segment, config.outlier_excursions) == ("max", False), "a name for a None default"


@pytest.mark.parametrize(
    ("item", "message"),
    [("bogus=1", "PipelineConfig setting"), ("outlier_window_s", "NAME=VALUE"), ("q_root_m=abc", "not a number"),
     ("outlier_window_s=-1", r"outlier_window_s\s+Input should be greater than 0"),
     ("outlier_segment=sometimes", "outlier_segment"), ("outlier_excursions=maybe", "not true/false")],
)  # fmt: skip
def test_bad_overrides_raise(item: str, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        pipeline_config([item])
