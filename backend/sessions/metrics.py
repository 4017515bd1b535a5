"""The metrics document of an uploaded session: the analysis report plus the four indicators."""

from __future__ import annotations

import math
from typing import Any

from backend.exercises.library import ExerciseSpec
from kinect_agent.formats.session_file import SessionPayload

# the version of the analysis a document was made by (doc["analysis_version"]); raise it when a metric's
# definition changes, so `coach-server reanalyze` knows which stored documents are older
ANALYSIS_VERSION = "2026.11.27-balance"


def metrics_document(
    payload: SessionPayload, spec: ExerciseSpec, *, target_reps: int | None, history: list[dict[str, Any]]
) -> dict[str, Any]:
    """Returns analyze_recording's document of the payload with an added "indicators" key.

    history: metrics documents of the patient's earlier sessions of the same exercise, oldest first.
    Raises backend.analysis.errors.AnalysisError when the recording cannot be analysed.
    """
    from backend.analysis.indicators import indicators
    from backend.analysis.report import analyze_recording

    doc = analyze_recording(payload.raw, spec, filtered=payload.filtered, angle_sd=payload.angle_sd)
    doc = json_ready(doc)
    doc["indicators"] = json_ready(indicators(doc, exercise=spec, target_reps=target_reps, history=history))
    doc["analysis_version"] = ANALYSIS_VERSION
    return doc


def scalar_columns(doc: dict[str, Any]) -> dict[str, Any]:
    """Returns the query columns of SessionMetric (repetitions, rom_deg, quality_ok, indicator_scores) read from a
    document."""
    reps = doc.get("repetitions")
    rom = doc.get("rom_deg")
    quality = doc.get("quality")
    return {
        "repetitions": reps if isinstance(reps, int) and not isinstance(reps, bool) else None,
        "rom_deg": _number(rom),
        "quality_ok": quality.get("ok") if isinstance(quality, dict) and isinstance(quality.get("ok"), bool) else None,
        "indicator_scores": indicator_scores(doc),
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


def json_ready(value: Any) -> Any:
    """Returns value with numpy scalars and arrays turned into Python numbers and lists, NaN and inf into None."""
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_ready(v) for v in value]
    if hasattr(value, "tolist") and not isinstance(value, str | bytes):
        return json_ready(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
