"""One session exported to a file in any of FORMATS: the bytes, their media type and a file name.

    csv   a zip of CSV tables (export.tables): one download that a spreadsheet opens table by table; metrics.csv and
          repetitions.csv need the server's analysis document, feeling.csv the patient's answers, the angle tables
          only the session file.
    trc   the filtered joint centres as an OpenSim marker file (export.trc), mm.
    bvh   the filtered recording as the kinematic model's motion (formats.bvh_writer), cm and degrees.
    fhir  an R4 Bundle of Observations (export.fhir); needs the analysis document.
The filtered recording is used where one is stored; a session without one falls back to the raw recording.
"""

from __future__ import annotations

import dataclasses
import io
import json
import zipfile
from dataclasses import dataclass
from typing import Literal, get_args

from kinect_agent.analysis.document import AnalysisReport
from kinect_agent.analysis.validity import recorded_with
from kinect_agent.errors import AgentError
from kinect_agent.export import fhir, tables, trc
from kinect_agent.formats import bvh_writer
from kinect_agent.formats.session_file import SessionPayload

ExportFormat = Literal["csv", "trc", "bvh", "fhir"]
FORMATS: tuple[ExportFormat, ...] = get_args(ExportFormat)
MEDIA_TYPES: dict[str, str] = {
    "csv": "application/zip",
    "trc": "text/plain; charset=utf-8",
    "bvh": "text/plain; charset=utf-8",
    "fhir": fhir.MEDIA_TYPE,
}
SUFFIXES: dict[str, str] = {"csv": "-csv.zip", "trc": ".trc", "bvh": ".bvh", "fhir": "-fhir.json"}
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)  # fixed member times: the same session gives the same bytes


class ExportError(AgentError):
    """A session cannot be exported in the requested format; says why."""


@dataclass(frozen=True)
class ExportFile:
    """An exported session: data bytes, media_type (HTTP Content-Type), file_name (e.g. session-12.trc)."""

    data: bytes
    media_type: str
    file_name: str


def _zip(members: dict[str, str]) -> bytes:
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED) as z:
        for name, text in members.items():
            z.writestr(zipfile.ZipInfo(name, _ZIP_TIME), text.encode("utf-8"), compress_type=zipfile.ZIP_DEFLATED)
    return out.getvalue()


def csv_zip(payload: SessionPayload, document: AnalysisReport | None, feeling: fhir.Feeling | None = None) -> bytes:
    """Returns the zip of metrics.csv, repetitions.csv (with a document), feeling.csv (with a feeling),
    recording.csv (the device) and angles_raw/angles_filtered.csv."""
    members: dict[str, str] = {}
    if feeling is not None:
        members["feeling.csv"] = tables.feeling_csv(feeling.pain_nrs, feeling.effort_cr10, feeling.answered_at)
    meta = payload.raw.meta
    if document is not None:
        members["metrics.csv"] = tables.metrics_csv(document, device=meta.device)
        members["repetitions.csv"] = tables.repetitions_csv(document)
    members["recording.csv"] = tables.recording_csv(recorded_with(meta.device, meta.extra), meta.rate_hz)
    members["angles_raw.csv"] = tables.angles_csv(payload.raw)
    if payload.filtered is not None:
        members["angles_filtered.csv"] = tables.angles_csv(payload.filtered, measured=True)
    return _zip(members)


def export(
    fmt: str,
    payload: SessionPayload,
    *,
    document: AnalysisReport | None = None,
    context: fhir.SessionContext | None = None,
    stem: str = "session",
) -> ExportFile:
    """Returns `payload` exported as `fmt` (one of FORMATS); raises ExportError for an unknown format or missing input.

    document: the session's analysis document (kinect_agent.analysis.report plus "indicators"); needed by fhir.
    context: ids for fhir (default: the file's session id and created_at, no patient or device), and how the set felt
    (fhir and csv). stem: file name stem.
    """
    if fmt not in FORMATS:
        raise ExportError(f"unknown export format {fmt!r}; expected one of {', '.join(FORMATS)}")
    rec = payload.filtered if payload.filtered is not None else payload.raw
    file_name = f"{stem}{SUFFIXES[fmt]}"
    if fmt == "csv":
        data = csv_zip(payload, document, context.feeling if context is not None else None)
    elif fmt == "trc":
        data = trc.write_text(rec.t, rec.positions, file_name=file_name).encode("utf-8")
    elif fmt == "bvh":
        try:
            data = bvh_writer.write_text(rec.t, rec.positions).encode("utf-8")
        except ValueError as exc:
            raise ExportError(f"cannot write BVH: {exc}") from None
    else:
        if document is None:
            raise ExportError("fhir needs the session's analysis document (the metrics the server computed)")
        context = context or fhir.SessionContext(session_id=payload.session_id, start=payload.created_at)
        if context.recorded_with is None:
            meta = payload.raw.meta
            context = dataclasses.replace(context, recorded_with=recorded_with(meta.device, meta.extra))
        data = json.dumps(fhir.bundle(document, context), indent=1, allow_nan=False).encode("utf-8")
    return ExportFile(data=data, media_type=MEDIA_TYPES[fmt], file_name=file_name)
