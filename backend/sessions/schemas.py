"""Session bodies: list items, progress series, the dashboard summary and rows."""

from __future__ import annotations

import datetime as dt
import uuid
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, JsonValue
from pydantic.config import JsonDict

from kinect_agent.analysis.document import Indicators
from kinect_agent.analysis.reasons import Reason


class SessionItemOut(BaseModel):
    """A stored session without its metrics document (list items)."""

    id: int = Field(examples=[31])
    client_session_id: uuid.UUID = Field(description="the session id written in the file by the home agent")
    patient_id: int = Field(examples=[12])
    device_id: int | None = Field(description="the device that uploaded it; null for uploads by a user")
    exercise_slug: str | None = Field(examples=["squat"])
    started_at: dt.datetime = Field(description="when the recording was made (the file's created_at), UTC")
    duration_s: float = Field(description="first to last frame of the raw recording, seconds", examples=[51.6])
    n_frames: int = Field(examples=[1551])
    file_size: int = Field(description="bytes of the stored .khs file", examples=[179324])
    content_hash: str = Field(description="SHA-256 of the file, 64 hex digits")
    status: str = Field(description="'processed', or 'failed' when the analysis could not use the recording")
    error: str | None = Field(description="why the analysis failed (status 'failed')")
    repetitions: int | None = Field(examples=[10])
    rom_deg: float | None = Field(description="range of motion of the defining angle, degrees", examples=[92.5])
    quality_ok: bool | None = None
    created_at: dt.datetime = Field(description="when the server stored it, UTC")
    file_removed_at: dt.datetime | None = Field(
        default=None,
        description="when the clinic's retention period removed the recording (the metrics stay), UTC; null: kept",
    )


_INDICATORS_EXAMPLE: JsonDict = {
    "flexibility": {
        "score": 60.7,
        "value": 82.0,
        "basis": {
            "id": "flexibility_normal_range",
            "params": {"angle": "knee_flexion_R", "low": 0, "high": 135},
            "text": "median amplitude of the right knee flexion over the repetitions, against its normal range of 0 "
            "to 135°",
        },
        "quality_ok": True,
        "previous": 58.1,
    },
    "endurance": {
        "score": 80.0,
        "value": 8,
        "basis": {"id": "endurance_target", "params": {"target": 10}, "text": "repetitions against the target of 10"},
        "quality_ok": True,
        "previous": 9.0,
    },
    "strength": {
        "score": 64.0,
        "value": 26.5,
        "basis": {
            "id": "strength_speed_best",
            "params": {},
            "text": "movement speed (°/s) against the best earlier session",
        },
        "quality_ok": True,
        "previous": 30.1,
    },
    "balance": {
        "score": None,
        "value": None,
        "basis": {
            "id": "balance_sway",
            "params": {"good": 1, "poor": 6},
            "text": "sway of the trunk and hips while standing: 1 cm/s scores 100, 6 cm/s scores 0",
        },
        "quality_ok": False,
        "previous": 0.021,
        "interval": None,
        "missing": {
            "id": "not_standing",
            "params": {},
            "text": "the patient was seated or crouching: balance is measured while standing",
        },
    },
}


class ProgressPoint(BaseModel):
    """One session of a progress series."""

    session_id: int
    exercise_slug: str | None
    started_at: dt.datetime
    repetitions: int | None
    rom_deg: float | None = Field(description="degrees")
    quality_ok: bool | None
    indicators: Indicators | None = Field(
        description="flexibility, endurance, strength, balance (the session's metrics document); null: not analysed"
    )
    pain_nrs: int | None = Field(default=None, description="pain the patient said after the set, 0-10; null: not said")
    effort_cr10: float | None = Field(
        default=None, description="effort the patient said after the set, Borg CR10 0-10; null: not said"
    )


class ProgressOut(BaseModel):
    """A patient's sessions as a time series, oldest first."""

    model_config = ConfigDict(
        json_schema_extra={
            "examples": [
                {
                    "patient_id": 12,
                    "exercise_slug": "seated_knee_extension",
                    "points": [
                        {
                            "session_id": 301,
                            "exercise_slug": "seated_knee_extension",
                            "started_at": "2026-11-16T10:55:00Z",
                            "repetitions": 10,
                            "rom_deg": 76.6,
                            "quality_ok": True,
                            "indicators": _INDICATORS_EXAMPLE,
                            "pain_nrs": 2,
                            "effort_cr10": 3.5,
                        }
                    ],
                }
            ]
        }
    )
    patient_id: int
    exercise_slug: str | None = Field(description="the exercise filtered on; null = every exercise")
    points: list[ProgressPoint]


class LastSessionOut(BaseModel):
    """The newest session of a patient, in brief."""

    id: int
    exercise_slug: str | None
    started_at: dt.datetime
    repetitions: int | None
    rom_deg: float | None
    quality_ok: bool | None


class IndicatorTrendOut(BaseModel):
    """One indicator's weekly medians over the last weeks (backend.sessions.triage)."""

    weeks: list[dt.date] = Field(description="Monday (UTC) of each week, oldest first; the last is the current week")
    weekly_median: list[float | None] = Field(description="median indicator score (0-100) per week; null = no data")
    direction: Literal["up", "down", "flat"] | None = Field(
        description="latest week with data against the earliest: ±5 points or more; null with under two weeks of data"
    )
    text: str = Field(description="the trend in words", examples=["Flexibility rose from 48 to 60 over 4 weeks"])


_TREND_WEEKS_EXAMPLE: list[JsonValue] = [
    "2026-10-19",
    "2026-10-26",
    "2026-11-02",
    "2026-11-09",
    "2026-11-16",
    "2026-11-23",
]
_TRENDS_EXAMPLE: JsonDict = {
    "flexibility": {
        "weeks": _TREND_WEEKS_EXAMPLE,
        "weekly_median": [66.0, 64.5, 61.0, None, 55.2, 50.0],
        "direction": "down",
        "text": "Flexibility fell from 66 to 50 over 5 weeks",
    },
    "endurance": {
        "weeks": _TREND_WEEKS_EXAMPLE,
        "weekly_median": [80.0, 80.0, 90.0, None, 80.0, 80.0],
        "direction": "flat",
        "text": "Endurance held steady from 80 to 80 over 5 weeks",
    },
    "strength": {
        "weeks": _TREND_WEEKS_EXAMPLE,
        "weekly_median": [None, None, None, None, None, 64.0],
        "direction": None,
        "text": "Strength: not enough weeks with data for a trend",
    },
    "balance": {
        "weeks": _TREND_WEEKS_EXAMPLE,
        "weekly_median": [None, None, None, None, None, None],
        "direction": None,
        "text": "Balance: not enough weeks with data for a trend",
    },
}


class SummaryOut(BaseModel):
    """What a therapist's dashboard shows about one patient."""

    model_config = ConfigDict(
        json_schema_extra={
            "examples": [
                {
                    "patient_id": 12,
                    "last_session": {
                        "id": 318,
                        "exercise_slug": "seated_knee_extension",
                        "started_at": "2026-11-23T10:55:00Z",
                        "repetitions": 9,
                        "rom_deg": 67.5,
                        "quality_ok": True,
                    },
                    "sessions_this_week": 2,
                    "planned_this_week": 6,
                    "latest_indicators": _INDICATORS_EXAMPLE,
                    "pending_suggestions": 2,
                    "unread_replies": 1,
                    "attention_score": 72,
                    "attention_level": "now",
                    "attention_reasons": [
                        "Behind this week's plan: 2 of the 4 sessions due by now done (6 a week planned)",
                        "Range of motion of seated knee extension fell from 90° to 67° "
                        "(last 7 days vs the 4 weeks before)",
                        "1 suggestion to review",
                    ],
                    "indicator_trends": _TRENDS_EXAMPLE,
                    "balance_missing": "Not measured: no still standing of 2 s or more in the last session "
                    "(seated knee extension)",
                }
            ]
        }
    )
    patient_id: int
    last_session: LastSessionOut | None
    sessions_this_week: int = Field(description="sessions started since Monday 00:00 UTC of the current week")
    planned_this_week: int | None = Field(
        description="sessions per week the running plans prescribe (sum over their items); null without a plan"
    )
    latest_indicators: Indicators | None = Field(description="indicators of the newest processed session")
    pending_suggestions: int = Field(description="system suggestions waiting for a therapist's decision")
    unread_replies: int = Field(description="the patient's replies to advice no therapist has read yet")
    attention_score: int = Field(ge=0, le=100, description="how much the patient needs attention (triage formula)")
    attention_level: Literal["now", "soon", "ok"] = Field(description="'now' at score ≥ 50, 'soon' at ≥ 20")
    attention_reasons: list[str] = Field(description="what adds to the score, in words, largest first")
    indicator_trends: dict[str, IndicatorTrendOut] = Field(
        description="per indicator (flexibility, endurance, strength, balance), weekly medians over 6 weeks"
    )
    balance_missing: str | None = Field(
        description="why the latest indicators have no balance score, in words; null when they have one"
    )


class DashboardRowOut(SummaryOut):
    """One patient of the therapist dashboard: who they are and their summary."""

    full_name: str = Field(examples=["Pat Jones"])
    email: str = Field(examples=["pat@example.org"])


class BalanceOut(BaseModel):
    """Sway of the trunk-and-hips centre of mass while standing (kinect_agent.analysis.balance)."""

    sway_velocity_m_s: float = Field(description="path of the centre of mass on the floor per second standing, m/s")
    sway_velocity_95: list[float] | None = Field(description="95 % interval [low, high] of the velocity, m/s")
    sway_area_m2: float | None = Field(description="95 % confidence ellipse of the floor positions, m²")
    standing_s: float | None = Field(description="standing time measured, s")


class CurveOut(BaseModel):
    """One joint-angle curve of a session, thinned by min/max decimation (backend.session_texts.session_detail)."""

    angle: str = Field(description="clinical angle name (kinect_agent.body.angles)", examples=["knee_flexion_R"])
    kind: str = Field(description="'raw', 'filtered', or 'smoothed' (raw smoothed: the file had no filtered one)")
    label: str = Field(description="a legend label in words, in the reader's language",
                       examples=["right knee flexion, filtered"])  # fmt: skip
    angle_label: str = Field(description="the angle in words, in the reader's language",
                             examples=["right knee flexion"])  # fmt: skip
    kind_label: str = Field(description="the kind in words, in the reader's language",
                            examples=["filtered"])  # fmt: skip
    t_s: list[float] = Field(description="seconds from the session's first frame")
    deg: list[float | None] = Field(description="degrees; null where the joints were not tracked")


class RepetitionDetailOut(BaseModel):
    """One repetition of the per-repetition table."""

    index: int = Field(description="0-based, in time order")
    start_s: float = Field(description="seconds from the session's first frame")
    end_s: float
    duration_s: float
    rom_deg: float | None = Field(
        description="range of motion (amplitude) of the defining angle, degrees; null: withheld (why in withheld)"
    )
    peak_deg: float | None = Field(
        description="the defining angle at the repetition's peak, degrees; null: withheld (why in withheld)"
    )
    peak_speed_deg_s: float | None = Field(
        description="largest angular speed of the defining angle, deg/s; null: unknown, or withheld with rom_deg"
    )
    side: str = Field(description="'left', 'right', 'both' or 'center'")
    withheld: str | None = Field(
        default=None,
        description="why rom_deg, peak_deg and peak_speed_deg_s are null, in the reader's language: the curve "
        "passed what the joint bends (the camera lost the limb); null when they are shown",
    )
    withheld_reason: Reason | None = Field(
        default=None, description="withheld for machines: the analysis' message id and numbers, with its text"
    )


class JointPathOut(BaseModel):
    """How far one joint travelled during the session."""

    joint: str
    path_m: float = Field(description="path length, metres")


class HandWorkspaceOut(BaseModel):
    """The reachable workspace of one arm (kinect_agent.analysis.reachable) and the hand's path, in arm lengths."""

    arm_length_m: float | None
    area_ratio: float | None = Field(description="reached fraction of the frontal hemisphere's surface, 0..1")
    volume_ratio: float | None = Field(description="reached fraction of the hemisphere's volume, 0..1")
    quadrants: dict[str, float] | None = Field(description="area ratio per quarter of the hemisphere, 0..1")
    outward: list[float | None] = Field(description="hand − shoulder along the trunk's outward axis, arm lengths")
    up: list[float | None] = Field(description="... along the trunk's up axis, arm lengths")
    forward: list[float | None] = Field(description="... along the trunk's forward axis, arm lengths")


class WorkspaceOut(BaseModel):
    """The reachable workspace of both arms (arm exercises only)."""

    left: HandWorkspaceOut | None
    right: HandWorkspaceOut | None


class QualityPartOut(BaseModel):
    """One part of the data-quality score (backend.session_texts.data_quality)."""

    name: str = Field(description="'tracked_fraction', 'outlier_fraction' or 'segment_spread_mm'")
    label: str = Field(description="the part in words, in the reader's language")
    value: float | None = Field(description="fraction 0..1, or millimetres for segment_spread_mm")
    score: int | None = Field(description="0..100")
    weight: float = Field(description="weight in the total score")


class AdviceOut(BaseModel):
    """One piece of camera advice in plain words (backend.session_texts.camera_advice)."""

    code: str = Field(
        description="too_close, too_far, off_centre, hand_out_of_view, foot_out_of_view or feet_cut_off: stable, "
        "whatever the language of the text",
        examples=["too_close"],
    )
    params: dict[str, float | str] = Field(
        default_factory=dict,
        description="what the advice was found from: distance_m (too_close, too_far, off_centre), sides "
        "('left', 'right', 'both') and fraction 0..1 (hand/foot_out_of_view); empty for advice stored before them",
        examples=[{"distance_m": 1.21}],
    )
    text: str = Field(description="the advice in the reader's language (Accept-Language; a patient's chosen one)")


class OutlierStripOut(BaseModel):
    """Per-frame outlier probability per joint of the raw recording, max-pooled into columns over time."""

    joints: list[str]
    t_s: list[float] = Field(description="centre of each column, seconds from the first frame")
    column_s: float = Field(description="width of a column, seconds")
    prob: list[list[float | None]] = Field(description="one row per joint, one value 0..1 per column; null = unseen")
    threshold: float = Field(description="probability above which a sample counts as a tracking error")


class DataQualityOut(BaseModel):
    """The session's data quality: a 0-100 score, its parts, the outlier timeline and camera advice."""

    score: int = Field(description="0..100")
    low: bool = Field(description="score at or below the low mark (70): read the numbers with care")
    parts: list[QualityPartOut]
    segment_spread_mm: dict[str, float | None] = Field(description="robust spread of each segment's raw length, mm")
    outlier_strip: OutlierStripOut
    advice: list[AdviceOut]
    analysis_ok: bool | None = Field(description="the analysis' own quality check (metrics document), if any")
    analysis_reasons: list[str] = Field(description="why the analysis' check failed, in the reader's language")
    analysis_reason_items: list[Reason] = Field(
        default_factory=list,
        description="analysis_reasons for machines, in the same order: each its message id and numbers (id null: a "
        "text an older analysis stored) with its text",
    )


class ProcessingOut(BaseModel):
    """How the session was processed: versions and parameters."""

    version: str = Field(description="server version that processed the upload", examples=["0.4.0"])
    params: dict[str, Any] = Field(description="parameters stored with the session (from the file's params)")
    file_params: dict[str, Any] = Field(description="the params written in the session file by the home agent")
    filter_history: list[str] = Field(description="processing steps of the filtered recording, oldest first")
    analysis: str = Field(description="'stored' (the metrics document) or 'recomputed' (none was stored)")


class AngleUncertaintyOut(BaseModel):
    """One angle's range of motion (1st / 99th percentiles, degrees) with 95 % intervals
    (kinect_agent/analysis/intervals.py)."""

    min_deg: float | None = Field(description="1st percentile of the angle, degrees")
    max_deg: float | None = Field(description="99th percentile: the peak angle, degrees", examples=[131.2])
    range_deg: float | None = Field(description="max_deg − min_deg, degrees", examples=[118.4])
    min_ci95: list[float] | None = Field(description="95 % interval [low, high] of min_deg; null: none")
    max_ci95: list[float] | None = Field(description="95 % interval of max_deg", examples=[[108.3, 154.1]])
    range_ci95: list[float] | None = Field(description="95 % interval of range_deg", examples=[[96.0, 140.8]])
    withheld: str | None = Field(
        default=None,
        description="why the intervals are not shown (poor tracking, undefined, too wide), in the reader's language; "
        "null: shown",
    )
    withheld_reason: Reason | None = Field(
        default=None, description="withheld for machines: its message id and numbers, with its text; null: shown"
    )


class CountIntervalOut(BaseModel):
    """The repetition count under perturbed angles: low..high; ambiguous when they differ."""

    low: int = Field(examples=[9])
    high: int = Field(examples=[10])
    ambiguous: bool


class UncertaintyOut(BaseModel):
    """95 % intervals of the session's figures from the per-frame angle SDs stored in its file."""

    angles: dict[str, AngleUncertaintyOut] = Field(description="by angle name (every angle with an interval)")
    repetitions: CountIntervalOut | None = Field(description="interval of the repetition count")
    peak_end: str = Field(
        default="max",
        description="'max' or 'min': the end of the defining angle's range its repetitions peak at (the peak angle)",
    )


class RecordedWithOut(BaseModel):
    """What recorded the session: the device, and for an ordinary camera the pose model and the frame rate."""

    device: str = Field(description="kinect_agent.recording.DEVICES code", examples=["webcam"])
    label: str = Field(description="the device in words", examples=["ordinary camera (webcam)"])
    model: str | None = Field(description="pose model file (webcam only)", examples=["pose_landmarker_lite.task"])
    model_sha256: str | None = Field(description="SHA-256 of the pose model file (webcam only)")
    runtime: str | None = Field(description="the pose runtime and its version (webcam only)")
    fps_achieved: float | None = Field(description="images analysed per second during the recording (webcam)")


class MetricValidityOut(BaseModel):
    """Whether one metric is valid for the device and view (kinect_agent.analysis.validity)."""

    name: str = Field(description="an angle name, 'rom', 'repetitions', 'workspace', 'balance', ...")
    valid: bool
    code: str | None = Field(description="'out_of_plane' or 'metric_scale' when not valid")
    reason: str | None = Field(description="why not, in plain words")


class ValidityOut(BaseModel):
    """Which of the session's metrics its device and view support."""

    device: str
    view: str = Field(description="'front', 'side', 'oblique' or 'unknown'")
    view_deg: float | None = Field(description="the trunk's angle to the camera axis, degrees (0 facing it)")
    limited: bool = Field(description="some metric is not valid for this device and view")
    metrics: list[MetricValidityOut]


class PreparingOut(BaseModel):
    """Where a result a worker prepares is: being prepared (ask again in a few seconds) or failed (why, in words)."""

    model_config = ConfigDict(
        json_schema_extra={"examples": [{"state": "preparing", "detail": "The session's detail is queued."}]}
    )
    state: Literal["preparing", "failed"] = Field(description="preparing: ask again in a few seconds")
    detail: str


class SessionDetailOut(BaseModel):
    """What the therapist's session page shows: the evidence behind the session's numbers."""

    model_config = ConfigDict(
        json_schema_extra={
            "examples": [
                {
                    "session_id": 31,
                    "patient_id": 12,
                    "exercise_slug": "squat",
                    "exercise_name": "Mini squat",
                    "started_at": "2026-11-20T10:00:00Z",
                    "status": "processed",
                    "error": None,
                    "duration_s": 51.6,
                    "n_frames": 1551,
                    "rate_hz": 30.0,
                    "measured_on": "filtered",
                    "repetition_count": 1,
                    "rom_deg": 62.4,
                    "rom_deg_withheld": None,
                    "rom_deg_withheld_reason": None,
                    "defining_angle": "knee_flexion_R",
                    "moving_time_s": 40.2,
                    "rest_time_s": 11.4,
                    "tempo_s_per_rep": 4.8,
                    "balance": None,
                    "balance_missing": "the patient was seated or crouching: balance is measured while standing",
                    "balance_missing_reason": {
                        "id": "not_standing",
                        "params": {},
                        "text": "the patient was seated or crouching: balance is measured while standing",
                    },
                    "angles": ["knee_flexion_R"],
                    "curves": [
                        {
                            "angle": "knee_flexion_R",
                            "kind": "raw",
                            "label": "right knee flexion, raw",
                            "angle_label": "right knee flexion",
                            "kind_label": "raw",
                            "t_s": [0.0, 2.1, 4.3],
                            "deg": [4.1, 66.0, None],
                        },
                        {
                            "angle": "knee_flexion_R",
                            "kind": "filtered",
                            "label": "right knee flexion, filtered",
                            "angle_label": "right knee flexion",
                            "kind_label": "filtered",
                            "t_s": [0.0, 2.1, 4.3],
                            "deg": [3.2, 64.8, 3.9],
                        },
                    ],
                    "repetitions": [
                        {
                            "index": 0,
                            "start_s": 0.4,
                            "end_s": 4.1,
                            "duration_s": 3.7,
                            "rom_deg": 62.4,
                            "peak_deg": 64.8,
                            "peak_speed_deg_s": 71.5,
                            "side": "both",
                            "withheld": None,
                            "withheld_reason": None,
                        }
                    ],
                    "most_moving_joints": [{"joint": "KNE_R", "path_m": 3.412}],
                    "workspace": None,
                    "quality": {
                        "score": 86,
                        "low": False,
                        "parts": [
                            {
                                "name": "tracked_fraction",
                                "label": "Body seen by the camera",
                                "value": 0.998,
                                "score": 100,
                                "weight": 0.4,
                            }
                        ],
                        "segment_spread_mm": {"LEG_LO_R": 18.6},
                        "outlier_strip": {
                            "joints": ["KNE_R"],
                            "t_s": [0.05, 0.15],
                            "column_s": 0.1,
                            "prob": [[0.01, 0.97]],
                            "threshold": 0.95,
                        },
                        "advice": [],
                        "analysis_ok": True,
                        "analysis_reasons": [],
                        "analysis_reason_items": [],
                    },
                    "processing": {
                        "version": "0.4.0",
                        "params": {"pipeline": "ukf-4pass v1"},
                        "file_params": {"pipeline": "ukf-4pass v1"},
                        "filter_history": ["ukf-4pass v1 (four_pass; 12 outliers removed)"],
                        "analysis": "stored",
                    },
                    "uncertainty": {
                        "angles": {
                            "knee_flexion_R": {
                                "min_deg": 2.1,
                                "max_deg": 88.5,
                                "range_deg": 86.4,
                                "min_ci95": [0.0, 6.2],
                                "max_ci95": [31.9, 145.1],
                                "range_ci95": [35.1, 137.7],
                            }
                        },
                        "repetitions": {"low": 10, "high": 10, "ambiguous": False},
                    },
                    "uncertainty_note": "95 % intervals from the per-frame angle SDs the home agent stored",
                    "recorded_with": {
                        "device": "kinect2",
                        "label": "Kinect v2",
                        "model": None,
                        "model_sha256": None,
                        "runtime": None,
                        "fps_achieved": None,
                    },
                    "validity": {
                        "device": "kinect2",
                        "view": "front",
                        "view_deg": 4.5,
                        "limited": False,
                        "metrics": [{"name": "rom", "valid": True, "code": None, "reason": None}],
                    },
                }
            ]
        }
    )
    session_id: int
    patient_id: int
    exercise_slug: str | None
    exercise_name: str | None
    started_at: dt.datetime
    status: str
    error: str | None
    duration_s: float = Field(description="first to last frame, seconds")
    n_frames: int
    rate_hz: float | None
    measured_on: str = Field(description="what the metrics measured: 'filtered' or 'raw'")
    repetition_count: int
    rom_deg: float | None = Field(
        description="median range of motion over the repetitions, degrees; null: no repetition, or withheld"
    )
    rom_deg_withheld: str | None = Field(
        default=None,
        description="why rom_deg is null though repetitions were counted, in the reader's language: some were "
        "measured past what the joint bends; null when shown",
    )
    rom_deg_withheld_reason: Reason | None = Field(
        default=None, description="rom_deg_withheld for machines: the analysis' message id and numbers, with its text"
    )
    defining_angle: str | None
    moving_time_s: float | None
    rest_time_s: float | None
    tempo_s_per_rep: float | None
    balance: BalanceOut | None = Field(description="trunk-and-hips sway while standing; null: not measured")
    balance_missing: str | None = Field(
        description="why balance is not measured, in the reader's language; null when it is"
    )
    balance_missing_reason: Reason | None = Field(
        default=None,
        description="balance_missing for machines: the analysis' message id and numbers, with its text; null when "
        "balance is measured or the document is older than balance in standing phases",
    )
    angles: list[str] = Field(description="the exercise's defining angles the curves show")
    curves: list[CurveOut]
    repetitions: list[RepetitionDetailOut]
    most_moving_joints: list[JointPathOut]
    workspace: WorkspaceOut | None = Field(description="arm exercises only")
    quality: DataQualityOut
    processing: ProcessingOut
    uncertainty: UncertaintyOut | None = Field(
        description="95 % intervals of the figures; null: the session file stores no angle SDs (older agents)"
    )
    uncertainty_note: str
    recorded_with: RecordedWithOut
    validity: ValidityOut
