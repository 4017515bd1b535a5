"""CSV tables of a session, for a spreadsheet: metrics, repetitions, joint angles over time (raw and filtered).

Every table is comma-separated UTF-8 with a header row, numbers with a dot, empty cells for unknown values.
    metrics.csv       metric, value, unit: duration, frames, rate, repetitions, median repetition amplitude (and
                      why it is withheld, empty when shown), the range of motion of every angle (min, max, range)
                      and the four indicators (score, value).
    repetitions.csv   one row per repetition of the analysis document's repetition_list (its keys as columns; a
                      withheld amplitude and peak empty, `withheld` why).
    angles_raw.csv, angles_filtered.csv   time_s then every clinical angle (body.angles.ANGLE_NAMES) in
                      degrees, one row per frame: of the raw recording frame by frame (the session page's raw
                      curves), and of the filtered recording as the analysis measures it (analysis.angles.
                      measured_angles, the session page's filtered curves and the range of motion); empty where
                      an angle is undefined.
    feeling.csv       (server exports of a session the patient answered for) pain_nrs (0-10 numeric rating
                      scale), effort_borg_cr10 (0-10 in halves), answered_at (ISO 8601 UTC); empty = skipped.
The metrics and repetitions come from the server's analysis document (kinect_agent.analysis.report.analyze_recording
plus "indicators"); the angles from the session file itself.
"""

from __future__ import annotations

import csv
import io
from typing import Any

import numpy as np

from kinect_agent.analysis.angles import measured_angles
from kinect_agent.analysis.document import AnalysisDocument, AnalysisReport, RepetitionItem
from kinect_agent.analysis.reasons import Reason
from kinect_agent.body.angles import ANGLE_NAMES, joint_angles
from kinect_agent.recording import Recording

INDICATORS = ("flexibility", "endurance", "strength", "balance")
_INDICATOR_UNITS = {"flexibility": "deg", "endurance": "repetitions", "strength": "deg/s", "balance": "m/s"}


def _cell(value: Any) -> str:
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def _text(rows: list[list[Any]]) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\r\n")
    for row in rows:
        writer.writerow([_cell(v) for v in row])
    return out.getvalue()


def metric_rows(document: AnalysisReport) -> list[tuple[str, Any, str]]:
    """Returns (metric, value, unit) rows of an analysis document (missing values as None; the indicators' rows
    empty without indicators)."""
    rows: list[tuple[str, Any, str]] = [
        ("exercise", document.exercise, ""),
        ("duration", document.duration_s, "s"),
        ("frames", document.n_frames, ""),
        ("frame_rate", document.rate_hz, "Hz"),
        ("repetitions", document.repetitions, ""),
        ("defining_angle", document.defining_angle, ""),
        ("repetition_amplitude_median", document.rom_deg, "deg"),
        ("repetition_amplitude_median.withheld", _reason_cell(document.rom_deg_withheld), ""),
        ("moving_time", document.moving_time_s, "s"),
        ("rest_time", document.rest_time_s, "s"),
    ]
    for angle, rom in document.range_of_motion.items():
        rows += [(f"{angle}.min", rom.min_deg, "deg"), (f"{angle}.max", rom.max_deg, "deg")]
        rows += [(f"{angle}.range", rom.range_deg, "deg")]
    indicators = document.indicators if isinstance(document, AnalysisDocument) else None
    for name in INDICATORS:
        item = getattr(indicators, name) if indicators is not None else None
        rows += [(f"indicator.{name}.score", item.score if item is not None else None, "0-100")]
        unit = "s" if name == "strength" and document.exercise == "sit_to_stand" else _INDICATOR_UNITS[name]
        rows += [(f"indicator.{name}.value", item.value if item is not None else None, unit)]
    return rows


def metrics_csv(document: AnalysisReport, device: str | None = None) -> str:
    """Returns metrics.csv: columns metric, value, unit; a first row names the recording device when given."""
    rows = ([("device", device, "")] if device is not None else []) + metric_rows(document)
    table: list[list[Any]] = [["metric", "value", "unit"], *[list(r) for r in rows]]
    return _text(table)


def recording_csv(recorded: dict[str, Any], rate_hz: float | None) -> str:
    """Returns recording.csv: what recorded the session (kinect_agent.analysis.validity.recorded_with), one
    field, value row each."""
    fields = ("device", "label", "model", "model_sha256", "runtime", "fps_achieved")
    rows: list[list[Any]] = [["field", "value"], *[[k, recorded.get(k)] for k in fields]]
    return _text([*rows, ["rate_hz", rate_hz]])


def _reason_cell(reason: Reason | None) -> str | None:
    """Returns a reason as one cell: its text when written (the server's exports write them in English), else its
    message id; None when there is none."""
    return None if reason is None else reason.text or reason.id


def repetitions_csv(document: AnalysisReport) -> str:
    """Returns repetitions.csv: a 1-based `repetition` column then the keys of each repetition_list entry; a
    withheld amplitude and peak are empty cells, and `withheld` says why."""
    reps = [r.model_dump(mode="json") | {"withheld": _reason_cell(r.withheld)} for r in document.repetition_list]
    keys = list(RepetitionItem.model_fields) if reps else []
    return _text([["repetition", *keys], *[[i + 1, *[rep.get(k) for k in keys]] for i, rep in enumerate(reps)]])


def angles_csv(recording: Recording, *, measured: bool = False) -> str:
    """Returns time_s and every clinical angle (degrees, 0.01°) per frame of a recording; time from the first frame.

    measured: the angles as the analysis measures them (gap-filled, smoothed positions), else frame by frame."""
    angles = measured_angles(recording.t, recording.positions).angles if measured else joint_angles(recording.positions)
    t = recording.t - recording.t[0]
    columns = [np.round(t, 6)] + [np.round(angles[name], 2) for name in ANGLE_NAMES]
    header = ["time_s", *[f"{name}_deg" for name in ANGLE_NAMES]]
    body = np.stack(columns, axis=1).tolist()
    return _text([header, *body])


def feeling_csv(pain_nrs: int | None, effort_cr10: float | None, answered_at: str | None) -> str:
    """Returns feeling.csv: one row of what the patient answered after the set (empty cells: skipped)."""
    return _text([["pain_nrs", "effort_borg_cr10", "answered_at"], [pain_nrs, effort_cr10, answered_at]])
