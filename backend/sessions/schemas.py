"""Session bodies: a stored session with its metrics, list items, progress series, the dashboard summary and rows."""

from __future__ import annotations

import datetime as dt
import uuid

from pydantic import BaseModel, ConfigDict, Field

from backend.suggestions.schemas import SuggestionOut


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


class SessionOut(SessionItemOut):
    """A stored session with its metrics document and the suggestions it produced that the caller may see."""

    metrics: dict | None = Field(description="the analysis document (backend.analysis.report) with 'indicators'")
    suggestions: list[SuggestionOut]


_INDICATORS_EXAMPLE = {
    "flexibility": {
        "score": 60.7,
        "value": 82.0,
        "basis": "median amplitude of knee_flexion_R against the normal range 0..135 deg",
        "quality_ok": True,
        "previous": 58.1,
    },
    "endurance": {"score": 80.0, "value": 8, "basis": "repetitions against the target of 10", "quality_ok": True},
    "strength": {
        "score": 64.0,
        "value": 26.5,
        "basis": "movement speed (deg/s) against the last weeks",
        "quality_ok": True,
    },
    "balance": {"score": None, "value": None, "basis": "body-centre sway while standing still", "quality_ok": False},
}


class ProgressPoint(BaseModel):
    """One session of a progress series."""

    session_id: int
    exercise_slug: str | None
    started_at: dt.datetime
    repetitions: int | None
    rom_deg: float | None = Field(description="degrees")
    quality_ok: bool | None
    indicators: dict | None = Field(description="flexibility, endurance, strength, balance: {score 0..100, ...}")


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
    latest_indicators: dict | None = Field(description="indicators of the newest processed session")
    pending_suggestions: int = Field(description="system suggestions waiting for a therapist's decision")


class DashboardRowOut(SummaryOut):
    """One patient of the therapist dashboard: who they are and their summary."""

    full_name: str = Field(examples=["Pat Jones"])
    email: str = Field(examples=["pat@example.org"])
