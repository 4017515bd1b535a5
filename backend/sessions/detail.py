"""The therapist's session page: a stored session's file decoded and measured again for the evidence behind its
numbers (backend.session_texts.session_detail, data_quality, camera_advice).

It costs seconds on a long recording (the outlier model), so a job-queue worker computes it once and keeps it in
the object store (backend.sessions.prepared); requests read that.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pydantic import ValidationError

from backend.exceptions import InvalidSessionFile
from backend.exercises.library import LIBRARY
from backend.i18n import ENGLISH, N_, Translator
from backend.jobs.listing import error_words
from backend.session_texts import data_quality, reasons, work_budget
from backend.session_texts.camera_advice import advice_text, camera_advice
from backend.session_texts.session_detail import (
    angle_curves,
    angular_speeds,
    curve_words,
    hand_paths,
    is_arm_exercise,
    measured_angles,
    peak_speeds,
)
from backend.sessions.models import ExerciseSession
from kinect_agent.analysis.document import AnalysisReport, RepetitionItem, UnreadableDocument, read_report
from kinect_agent.analysis.errors import AnalysisError
from kinect_agent.analysis.exercise import ExerciseSpec
from kinect_agent.analysis.reasons import Reason
from kinect_agent.analysis.validity import recorded_with, session_validity
from kinect_agent.formats import session_file
from kinect_agent.formats.session_file import SessionFileError, SessionPayload

DETAIL_VERSION = 5  # part of a stored detail's inputs (backend.sessions.prepared): bump when the output changes
# the texts of the therapist's session page (catalogue `therapist`): stored in English, written in the reader's
# language when read (in_language)
UNCERTAINTY_NOTE = N_(
    "95 % intervals from the per-frame angle SDs the home agent stored (the filter's covariance, calibrated on "
    "simulated sessions with known truth)."
)
NO_UNCERTAINTY_NOTE = N_(
    "The session file stores no per-frame uncertainty of the filtered recording (an older agent), "
    "so the numbers are shown without intervals."
)
BALANCE_NOT_MEASURED = N_(
    "this session was analysed before balance was measured in standing phases; a re-analysis measures it"
)
# kinect_agent.analysis.validity.REASONS as the pages show them (that layer cannot mark texts): English -> msgid
VALIDITY_REASONS = (
    N_(
        "This angle moves towards and away from the camera. One ordinary camera measures depth poorly, so the angle "
        "can be off by tens of degrees. Film the exercise from the side to measure it."
    ),
    N_(
        "This angle moves towards and away from the camera. One ordinary camera measures depth poorly, so the angle "
        "can be off by tens of degrees. Film the exercise from the front to measure it."
    ),
    N_("A turn about the arm's own axis cannot be seen in a camera image."),
    N_("The view could not be told from the recording, so this angle may lie out of the image plane."),
    N_(
        "Distances in metres come from an assumed camera and an average body size, not from a depth sensor: compare "
        "them only between sessions filmed the same way."
    ),
)


def decode_stored(data: bytes, *, session_id: int, max_frames: int, max_decoded_bytes: int) -> SessionPayload:
    """Returns the payload of a stored .khs file; raises InvalidSessionFile when it cannot be shown."""
    try:
        payload = session_file.decode(data, max_frames=max_frames, max_decoded_bytes=max_decoded_bytes)
    except SessionFileError as exc:
        raise InvalidSessionFile(
            f"the stored file of session {session_id} cannot be read: {exc.code}: {exc.detail}"
        ) from None
    if payload.raw.n_frames < 2:
        raise InvalidSessionFile(f"the stored file of session {session_id} has {payload.raw.n_frames} frame(s)")
    if payload.filtered is not None and payload.filtered.n_frames != payload.raw.n_frames:
        raise InvalidSessionFile(
            f"the stored file of session {session_id}: the filtered recording has {payload.filtered.n_frames} frames, "
            f"the raw one {payload.raw.n_frames}"
        )
    return payload


def analysis_document(
    payload: SessionPayload, spec: ExerciseSpec | None, stored: dict[str, Any] | None
) -> tuple[AnalysisReport | None, str]:
    """Returns (document, "stored" or "recomputed"): the stored one (any schema version), else analyze_recording's
    (None on failure)."""
    from kinect_agent.analysis.report import analyze_recording

    if stored is not None:
        try:
            return read_report(stored), "stored"
        except (ValidationError, UnreadableDocument):
            pass
    if spec is None:
        return None, "recomputed"
    try:
        return analyze_recording(payload.raw, spec, filtered=payload.filtered, angle_sd=payload.angle_sd), "recomputed"
    except (AnalysisError, ValueError):
        return None, "recomputed"


def file_evidence(payload: SessionPayload, names: tuple[str, ...], reps: list[RepetitionItem]) -> dict[str, Any]:
    """Returns the file-derived part of the detail: curves, repetition speeds, hand paths, quality and advice.

    payload: as analysed (work_budget.thinned: at most MAX_ANALYSIS_RATE_HZ frames per second).
    """
    raw, filtered = payload.raw, payload.filtered
    measured = filtered.positions if filtered is not None else raw.positions
    angles = measured_angles(raw.t, measured, names) if names else {}
    kind = "filtered" if filtered is not None else "smoothed"
    config = work_budget.SERVER_PIPELINE  # the file's params["config"] is shown, not obeyed (work_budget)
    prob = data_quality.outlier_probabilities(raw, config)
    quality = data_quality.assess(raw, prob, names, config.outlier_threshold)
    strip = data_quality.outlier_strip(raw.t, prob) | {"threshold": config.outlier_threshold}
    return {
        "curves": angle_curves(raw.t, raw.positions, angles, names, kind) if names else [],
        "peak_speeds": peak_speeds(raw.t, angular_speeds(raw.t, angles), reps),
        "hand_paths": hand_paths(measured, raw.t) if is_arm_exercise(names) else None,
        "quality": quality | {"outlier_strip": strip, "advice": camera_advice(raw)},
        "validity": session_validity(raw.meta.device, measured, names, names[0] if names else None).to_dict(),
    }


def _workspace(doc: AnalysisReport | None, paths: dict[str, Any] | None) -> dict[str, Any] | None:
    """Returns {"left", "right"}: each arm's stored workspace metrics with its hand path, or None."""
    if paths is None:
        return None
    reach = doc.reachable_range if doc is not None else None
    out: dict[str, Any] = {}
    for side in ("left", "right"):
        path, m = paths.get(side), getattr(reach, side) if reach is not None else None
        if path is None:
            out[side] = None
            continue
        out[side] = path | {
            "area_ratio": m.area_ratio if m is not None else None,
            "volume_ratio": m.volume_ratio if m is not None else None,
            "quadrants": m.quadrants if m is not None else None,
        }
    return out


def _rep_rows(reps: list[RepetitionItem], speeds: list[float | None]) -> list[dict[str, Any]]:
    """Returns the repetition table's rows (keys: RepetitionDetailOut); a withheld amplitude and peak are None, and
    so is the peak speed measured on the same lost curve, with why in English words (in_language writes them for a
    reader) and as a reason."""
    return [
        r.model_dump(include={"index", "start_s", "end_s", "duration_s", "peak_deg", "side"})
        | {"rom_deg": r.amplitude_deg, "peak_speed_deg_s": s if r.withheld is None else None}
        | {"withheld": _words(r.withheld), "withheld_reason": _reason_json(r.withheld)}
        for r, s in zip(reps, speeds, strict=True)
    ]


def _words(reason: Reason | None) -> str | None:
    """Returns a reason in English words (in_language writes it for a reader); None without one."""
    return None if reason is None else reasons.written(reason, ENGLISH)


def detail_body(
    session: ExerciseSession,
    slug: str | None,
    stored: dict[str, Any] | None,
    data: bytes,
    *,
    max_frames: int,
    max_decoded_bytes: int,
) -> dict[str, Any]:
    """Returns the detail body of a session row, its exercise slug, stored metrics document and file bytes."""
    payload = decode_stored(data, session_id=session.id, max_frames=max_frames, max_decoded_bytes=max_decoded_bytes)
    entry = LIBRARY.get(slug) if slug else None
    spec = entry.spec if entry is not None else None
    analysed = work_budget.thinned(payload)  # the work is bounded by the duration, whatever the frame rate
    doc, source = analysis_document(analysed, spec, stored)
    reps = doc.repetition_list if doc is not None else []
    evidence = file_evidence(analysed, tuple(spec.defining_angles) if spec is not None else (), reps)
    quality = doc.quality if doc is not None else None
    balance = _balance(doc)
    raw, filtered = payload.raw, payload.filtered
    return {
        "session_id": session.id,
        "patient_id": session.patient_id,
        "exercise_slug": slug,
        "exercise_name": entry.name if entry is not None else None,
        "started_at": session.started_at,
        "status": session.status,
        "error": session.error,
        "duration_s": round(raw.duration, 3),
        "n_frames": raw.n_frames,
        "rate_hz": round(raw.rate_hz, 3) if np.isfinite(raw.rate_hz) else None,
        "measured_on": doc.measured_on if doc is not None else ("filtered" if filtered is not None else "raw"),
        "repetition_count": len(reps),
        "rom_deg": doc.rom_deg if doc is not None else None,
        "rom_deg_withheld": _words(doc.rom_deg_withheld if doc is not None else None),
        "rom_deg_withheld_reason": _reason_json(doc.rom_deg_withheld if doc is not None else None),
        "defining_angle": doc.defining_angle if doc is not None else None,
        "moving_time_s": doc.moving_time_s if doc is not None else None,
        "rest_time_s": doc.rest_time_s if doc is not None else None,
        "tempo_s_per_rep": doc.tempo_s_per_rep if doc is not None else None,
        "balance": balance,
        "balance_missing": None if balance is not None else _balance_missing(doc),
        "balance_missing_reason": _reason_json(None if doc is None or balance is not None else doc.balance_missing),
        "angles": list(spec.defining_angles) if spec is not None else [],
        "curves": evidence["curves"],
        "repetitions": _rep_rows(reps, evidence["peak_speeds"]),
        "most_moving_joints": [j.model_dump() for j in doc.most_moving_joints] if doc is not None else [],
        "workspace": _workspace(doc, evidence["hand_paths"]),
        "quality": evidence["quality"]
        | {
            "analysis_ok": quality.ok if quality is not None else None,
            "analysis_reasons": [reasons.written(r, ENGLISH) for r in quality.reasons] if quality is not None else [],
            "analysis_reason_items": [_reason_json(r) for r in quality.reasons] if quality is not None else [],
        },
        "processing": {
            "version": session.processing_version or "",
            "params": session.processing_params or {},
            "file_params": payload.params if isinstance(payload.params, dict) else {},
            "filter_history": list(filtered.meta.history) if filtered is not None else [],
            "analysis": source,
        },
        "uncertainty": (uncertainty := _uncertainty(doc)),
        "uncertainty_note": UNCERTAINTY_NOTE if uncertainty is not None else NO_UNCERTAINTY_NOTE,
        "recorded_with": recorded_with(raw.meta.device, raw.meta.extra),
        "validity": evidence["validity"],
    }


def in_language(body: dict[str, Any], t: Translator) -> dict[str, Any]:
    """Returns a detail body (keys: SessionDetailOut, as stored in English) with its texts in t's language: why the
    session failed (the program's own words for a clinic's reader only), the curves' labels, the data-quality
    labels, the camera advice (from its code and params; advice stored before params keeps its text), the analysis'
    reasons (backend.session_texts.reasons), the uncertainty note, why balance was not measured, and the device's
    limits."""
    curves = [c | curve_words(c["angle"], c["kind"], t) for c in body.get("curves", [])]
    said: dict[str, Any] = {"curves": curves, "error": error_words(body.get("error"), t)}  # for every reader
    said |= _reasons_in(body, t)
    if t.locale == "en" and not t.therapist:
        return body | said
    quality = dict(said["quality"])
    quality["parts"] = [p | {"label": data_quality.part_label(p["name"], t)} if p["name"] in data_quality.PARTS
                        else p for p in quality["parts"]]  # fmt: skip
    quality["advice"] = [_advice_in(a, t) for a in quality["advice"]]
    shown = body | said | {"quality": quality}
    note = body.get("uncertainty_note")
    if note in (UNCERTAINTY_NOTE, NO_UNCERTAINTY_NOTE):
        shown["uncertainty_note"] = t.gettext(note)
    if body.get("balance_missing") == BALANCE_NOT_MEASURED:
        shown["balance_missing"] = t.gettext(BALANCE_NOT_MEASURED)
    validity = body.get("validity")
    if isinstance(validity, dict):
        metrics = [m | {"reason": _validity_reason(m.get("reason"), t)} for m in validity.get("metrics", [])]
        shown["validity"] = validity | {"metrics": metrics}
    return shown


def _reason_json(reason: Reason | None) -> dict[str, Any] | None:
    """Returns a reason as the stored detail keeps it: its id and numbers (or its text when it has no id)."""
    return None if reason is None else reason.model_dump(mode="json")


def _written(stored: object, t: Translator) -> Reason | None:
    """Returns a stored detail's reason with its text in t's language; None when there is none."""
    return None if stored is None else reasons.with_text(Reason.model_validate(stored), t)


def _reasons_in(body: dict[str, Any], t: Translator) -> dict[str, Any]:
    """Returns the detail's reasons written in t's language from their ids and numbers: the analysis' quality
    check (quality.analysis_reasons and its items), why balance was not measured, why an interval is withheld, why
    a repetition's numbers and the median amplitude are withheld."""
    quality = dict(body["quality"])
    items = [_written(r, t) for r in quality.get("analysis_reason_items", [])]
    quality["analysis_reason_items"] = [r.model_dump(mode="json") for r in items if r is not None]
    quality["analysis_reasons"] = [r.text for r in items if r is not None]
    out: dict[str, Any] = {"quality": quality}
    missing = _written(body.get("balance_missing_reason"), t)
    if missing is not None:
        out |= {"balance_missing": missing.text, "balance_missing_reason": missing.model_dump(mode="json")}
    rom = _written(body.get("rom_deg_withheld_reason"), t)
    if rom is not None:
        out |= {"rom_deg_withheld": rom.text, "rom_deg_withheld_reason": rom.model_dump(mode="json")}
    out["repetitions"] = [_withheld_in(r, t) for r in body.get("repetitions", [])]
    uncertainty = body.get("uncertainty")
    if isinstance(uncertainty, dict) and isinstance(uncertainty.get("angles"), dict):
        angles = {}
        for name, a in uncertainty["angles"].items():
            withheld = _written(a.get("withheld_reason"), t)
            angles[name] = (
                a
                if withheld is None
                else a | {"withheld": withheld.text, "withheld_reason": withheld.model_dump(mode="json")}
            )
        out["uncertainty"] = uncertainty | {"angles": angles}
    return out


def _withheld_in(row: dict[str, Any], t: Translator) -> dict[str, Any]:
    """Returns a repetition row with why its numbers are withheld in t's language (as it is when they are shown)."""
    why = _written(row.get("withheld_reason"), t)
    return row if why is None else row | {"withheld": why.text, "withheld_reason": why.model_dump(mode="json")}


def _validity_reason(reason: str | None, t: Translator) -> str | None:
    """Returns one of the device's limits (VALIDITY_REASONS) in t's language; any other text as it is."""
    return t.gettext(reason) if reason in VALIDITY_REASONS else reason


def _advice_in(item: dict[str, Any], t: Translator) -> dict[str, Any]:
    """Returns one piece of camera advice with its text in t's language (as stored when it cannot be rewritten)."""
    try:
        return item | {"text": advice_text(item["code"], item.get("params") or {}, t)}
    except (KeyError, TypeError, ValueError):
        return item


def _balance(doc: AnalysisReport | None) -> dict[str, Any] | None:
    """Returns the document's balance (keys: BalanceOut) when it holds a measured sway, else None."""
    if doc is None or doc.balance is None:
        return None
    return doc.balance.model_dump(include={"sway_velocity_m_s", "sway_velocity_95", "sway_area_m2", "standing_s"})


def _balance_missing(doc: AnalysisReport | None) -> str:
    """Returns why a document has no balance, in English words (in_language writes them for a reader)."""
    if doc is not None and doc.balance_missing is not None:
        return reasons.written(doc.balance_missing, ENGLISH)
    return BALANCE_NOT_MEASURED


def _uncertainty(doc: AnalysisReport | None) -> dict[str, Any] | None:
    """Returns the detail's uncertainty (keys: UncertaintyOut) from a document's 95 % intervals, or None.

    An angle whose intervals the analysis withheld is listed with null intervals and the reason."""
    if doc is None or doc.range_of_motion_95 is None:
        return None
    withheld = doc.range_of_motion_95_withheld or {}
    angles = {}
    for name, iv in doc.range_of_motion_95.items():
        value = doc.range_of_motion.get(name)
        if value is None or (iv is None and name not in withheld):
            continue
        angles[name] = (
            value.model_dump()
            | {
                "min_ci95": iv.min_deg if iv is not None else None,
                "max_ci95": iv.max_deg if iv is not None else None,
                "range_ci95": iv.range_deg if iv is not None else None,
            }
            | {
                "withheld": None if name not in withheld else reasons.written(withheld[name], ENGLISH),
                "withheld_reason": _reason_json(withheld.get(name)),
            }
        )
    reps = doc.repetitions_95.model_dump() if doc.repetitions_95 is not None else None
    return {"angles": angles, "repetitions": reps, "peak_end": doc.peak_end}
