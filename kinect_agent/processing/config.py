"""The settings of the signal pipeline (outlier removal, the four-pass UKF, the online filter), one frozen model.

Defaults were measured on simulated Kinect noise and real recordings; how each was chosen (measurements,
alternatives tried, dates) is in bench/README.md, section "Tuning history of the pipeline defaults", by field name.
A value out of range is refused when the model is built (pydantic.ValidationError, a ValueError naming the field).
"""

from __future__ import annotations

from typing import Literal, get_args

from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator

from kinect_agent.skeleton import SEGMENT_NAMES

Smoother = Literal["four_pass", "urts"]
OfflineFilter = Literal["chain", "joints"]
SMOOTHERS: tuple[str, ...] = get_args(Smoother)  # "urts" measured best; "four_pass" is the paper's


class PipelineConfig(BaseModel):
    """Settings of the pipeline (immutable: derive variants with model_copy(update=...) or by building a new one)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    sigma_tracked_m: float = Field(0.0325, gt=0, description="offline: measurement SD per axis of a tracked joint, m")
    sigma_inferred_m: float = Field(0.05, gt=0, description="measurement SD per axis of an inferred joint (state 1), m")
    q_root_m: float = Field(0.01, gt=0, description="random-walk SD of the root position per frame at rate_ref_hz, m")
    q_rot_rad: float = Field(0.08, gt=0, description="random-walk SD of each joint angle per frame at rate_ref_hz, rad")
    offline_q_rot_rad: float | None = Field(
        0.13, gt=0, description="offline: q_rot_rad of the four passes, rad (None: q_rot_rad)"
    )
    offline_q_root_m: float | None = Field(
        0.012, gt=0, description="offline: q_root_m of the four passes, m (None: q_root_m)"
    )
    q_length_m: float = Field(0.001, ge=0, description="random-walk SD of segment lengths per frame (passes 1-2), m")
    p0_root_m: float = Field(0.05, gt=0, description="initial SD of the root position, m")
    p0_rot_rad: float = Field(0.3, gt=0, description="initial SD of the joint angles, rad")
    p0_length_m: float = Field(0.03, gt=0, description="initial SD of segment lengths, m")
    rate_ref_hz: float = Field(30.0, gt=0, description="the frame rate at which the q_* values are per frame, Hz")
    remove_outliers: bool = Field(True, description="run the outlier removal (combined_outliers.py) first")
    outlier_threshold: float = Field(
        0.95, gt=0, lt=1, description="a sample is an outlier when P(uniform component) exceeds this"
    )
    outlier_window_s: float = Field(
        0.5, gt=0, description="window of the outlier residual's running median / local quadratic fit, s"
    )
    outlier_min_sigma_m: float = Field(0.015, description="floor of the outlier mixture's Gaussian SD per axis, m")
    outlier_min_range_m: float = Field(1.0, description="floor of the outlier mixture's uniform range per axis, m")
    outlier_iterations: int = Field(
        2, description="local-quadratic refinements of the outlier residual after its running median"
    )
    outlier_segment: Literal["max", "or", "and"] | None = Field(
        None,
        description='also a segment-length residual (segment_outliers.py) combined by "max"/"or", or "and" (a '
        "temporal outlier must break its bones too: min of both); None: no",
    )
    outlier_excursions: bool = Field(True, description="also flag sustained excursions offline (excursions.py)")
    online_excursions: bool = Field(True, description="online: hold out joints in an excursion (LiveExcursions)")
    excursion_min_dev_m: float = Field(
        0.2, gt=0, description="an excursion's jump away and median distance from the bridge, at least, m"
    )
    excursion_min_len_s: float = Field(0.3, gt=0, description="shortest excursion searched for, s")
    excursion_max_len_s: float = Field(3.0, description="longest excursion searched for, s (> excursion_min_len_s)")
    gate_chi2: float | None = Field(30.0, gt=0, description="offline: skip a joint whose innovation d² exceeds this")
    reacquire_s: float | None = Field(
        0.1, gt=0, description="offline: a joint gated this long restarts from inverse kinematics, s (None: never)"
    )
    online_reacquire_s: float | None = Field(
        0.3, gt=0, description="online: the same as reacquire_s when online_gate_chi2 is set, s (None: never)"
    )
    online_sigma_tracked_m: float = Field(
        0.07, gt=0, description="online: measurement SD per axis of a tracked joint, m"
    )
    online_gate_chi2: float | None = Field(
        None, gt=0, description="online: skip a joint whose innovation d² exceeds this (None: no gate)"
    )
    smoother: Smoother = Field(
        "urts", description='"urts": unscented RTS after pass 3; "four_pass": the paper\'s backward pass 4'
    )
    four_pass_combine: Literal["last", "information"] = Field(
        "last", description='four_pass output: "last" (pass 4) or "information" (passes 3 and 4 averaged)'
    )
    innovation_at_mean: bool = Field(
        False,
        description="UKF update (offline passes and online filter): innovation z − h(x̄), the mean state's joints, "
        "instead of z − Σ Wm·h(σ), the sigma points' mean; off: it removes the exact-input bias but loses on Kinect "
        "data (bench/README.md, Fast arm motion)",
    )
    fixed_innovation_at_mean: bool | None = Field(
        None,
        description="passes 3-4 (lengths fixed): innovation z − h(x̄) (True) or z − Σ Wm·h(σ) (False); None: as "
        "innovation_at_mean",
    )
    rigid_input_sd_m: float | None = Field(
        0.0005,
        gt=0,
        description="offline: a recording whose segment lengths spread less than this (noise_level.segment_noise_m) "
        "is exact, e.g. mocap or an already filtered recording, and is filtered with noise_level.rigid_settings, m "
        "(None: never)",
    )
    rigid_input_sigma_m: float = Field(
        0.01, gt=0, description="offline: measurement SD per axis of an exact input's joints (the chain's misfit), m"
    )
    alpha: float = Field(0.5, gt=0, description="sigma-point spread (van der Merwe)")
    beta: float = Field(2.0, description="sigma-point prior-distribution weight (van der Merwe; 2 for Gaussian)")
    kappa: float = Field(0.0, description="sigma-point secondary scaling (van der Merwe)")
    length_pass_max_frames: int | None = Field(
        6000, description="passes 1-2 (lengths) run over at most this many first frames (None or 0: every frame)"
    )
    online_init_s: float = Field(1.0, description="online: segment lengths are estimated over this first stretch, s")
    offset_model: bool = Field(
        False, description="subtract Kinect's per-joint body-frame offset (offset_model.py) from the offline output"
    )
    length_bias: dict[str, float] | None = Field(
        None,
        description="scale the estimated segment lengths by these factors (skeleton.SEGMENTS name -> truth / "
        "estimate; length_bias.py) before they are fixed, offline and online; None: off. Per device "
        "(length_bias.RATIOS)",
    )
    offline_filter: OfflineFilter = Field(
        "chain",
        description='offline: "chain", the four-pass kinematic UKF; "joints", each coordinate smoothed on its own '
        "(joint_smoother.py: no bone lengths, restarted at left/right label swaps)",
    )
    joint_sigma_image_m: float = Field(0.01, gt=0, description="joints filter: measurement SD along x and y, m")
    joint_sigma_depth_m: float = Field(0.025, gt=0, description="joints filter: measurement SD along z (depth), m")
    joint_accel_sd_mps2: float = Field(50.0, gt=0, description="joints filter: white acceleration SD, m/s²")
    joint_split_at_swaps: bool = Field(
        True, description="joints filter: restart at left/right label swaps and at jumps to another body"
    )
    joint_arm_swaps: bool = Field(
        True, description="joints filter, with joint_split_at_swaps: also restart where the arms alone swap labels"
    )

    @field_validator("length_bias")
    @classmethod
    def _segment_ratios(cls, value: dict[str, float] | None) -> dict[str, float] | None:
        if value is None:
            return value
        unknown = set(value) - set(SEGMENT_NAMES)
        if unknown:
            raise ValueError(f"not segments: {sorted(unknown)}")
        if not all(0.5 < v < 2.0 for v in value.values()):
            raise ValueError("each factor must lie in (0.5, 2)")
        return value

    @field_validator("excursion_max_len_s")
    @classmethod
    def _longer_than_min(cls, value: float, info: ValidationInfo) -> float:
        shortest = info.data.get("excursion_min_len_s")
        if shortest is not None and not value > shortest:
            raise ValueError(f"must exceed excursion_min_len_s ({shortest!r})")
        return value


# The measurement noise of each device where it differs from the defaults (Kinect v2, measured on KERAAL/UI-PRMD):
# webcam = BlazePose landmarks mapped by kinect_agent.sources.webcam.mapping; jitter and accuracy measured by
# bench/webcam_noise.py and bench/webcam_accuracy.py (bench/README.md, "Webcam").
# The webcam's offline output comes from the joints filter (bench/README.md, "Webcam angles: why the pipeline made
# them worse"); its chain settings serve the online filter of the live count.
DEVICE_SETTINGS: dict[str, dict[str, float | str | bool]] = {
    "webcam": {
        "sigma_tracked_m": 0.1,
        "sigma_inferred_m": 0.2,
        "online_sigma_tracked_m": 0.15,
        "offline_filter": "joints",
        "remove_outliers": False,
    },
}


def config_for_device(device: str | None) -> PipelineConfig:
    """Returns the pipeline settings for recordings of `device` (kinect_agent.recording.DEVICES; unknown or None:
    the defaults, which were measured on Kinect v2)."""
    return PipelineConfig.model_validate(DEVICE_SETTINGS.get(device or "", {}))


__all__ = ["DEVICE_SETTINGS", "SMOOTHERS", "OfflineFilter", "PipelineConfig", "config_for_device"]
