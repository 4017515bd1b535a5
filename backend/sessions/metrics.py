"""The metrics document of an uploaded session: the analysis report plus the four indicators
(kinect_agent.analysis.document.AnalysisDocument; stored as its model_dump(mode="json"))."""

from __future__ import annotations

from typing import Any

from kinect_agent.analysis.document import (
    AnalysisDocument,
    AnalysisReport,
    Indicators,
    json_ready,
)
from kinect_agent.analysis.exercise import ExerciseSpec
from kinect_agent.formats.session_file import SessionPayload

__all__ = ["ANALYSIS_VERSION", "indicator_scores", "json_ready", "metrics_document", "scalar_columns"]

# the version of the analysis a document was made by (doc["analysis_version"]); raise it when a metric's
# definition changes, so `coach-server reanalyze` knows which stored documents are older
ANALYSIS_VERSION = "2026.11.28-hip-limit-balance"  # hip flexion past 190° withheld; sway runs end at frame gaps


def metrics_document(
    payload: SessionPayload, spec: ExerciseSpec, *, target_reps: int | None, history: list[AnalysisReport]
) -> AnalysisDocument:
    """Returns analyze_recording's report of the payload with its indicators and today's analysis version.

    history: the documents of the patient's earlier sessions of the same exercise, oldest first
    (backend.sessions.history.session_history, its readable ones).
    Raises kinect_agent.analysis.errors.AnalysisError when the recording cannot be analysed.
    """
    from kinect_agent.analysis.indicators import indicators
    from kinect_agent.analysis.report import analyze_recording

    report = analyze_recording(payload.raw, spec, filtered=payload.filtered, angle_sd=payload.angle_sd)
    found = indicators(report, exercise=spec, target_reps=target_reps, history=history)
    return AnalysisDocument(**dict(report), indicators=found, analysis_version=ANALYSIS_VERSION)


def scalar_columns(doc: AnalysisDocument) -> dict[str, Any]:
    """Returns the query columns of SessionMetric (repetitions, rom_deg, quality_ok, indicator_scores) of a
    document."""
    return {
        "repetitions": doc.repetitions,
        "rom_deg": doc.rom_deg,
        "quality_ok": doc.quality.ok,
        "indicator_scores": {name: getattr(doc.indicators, name).score for name in Indicators.model_fields},
    }


def indicator_scores(doc: dict[str, Any]) -> dict[str, Any] | None:
    """Returns {indicator: score 0-100 or None} of a document's indicators (None without indicators): the small
    copy the dashboard's trends read instead of parsing whole documents."""
    indicators = doc.get("indicators")
    if not isinstance(indicators, dict):
        return None
    return {name: _number(v.get("score")) if isinstance(v, dict) else None for name, v in indicators.items()}


def _number(value: object) -> float | None:
    return float(value) if isinstance(value, int | float) and not isinstance(value, bool) else None
