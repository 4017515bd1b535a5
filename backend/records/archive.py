"""Everything the clinic holds about one patient, in one zip archive with a README inside."""

from __future__ import annotations

import datetime as dt
import json
import tempfile
import zipfile
from typing import IO, Any

from sqlalchemy import or_, select
from sqlalchemy.orm import Session

from backend.audit.models import AuditEvent
from backend.camera.models import CameraConsent, CameraSet
from backend.devices.models import Device
from backend.exceptions import SessionFileRemoved
from backend.exercises.models import Exercise
from backend.feeling.models import SessionFeeling
from backend.i18n import Translator, translator
from backend.jobs.models import SessionMetricVersion
from backend.patients.models import TherapistPatient
from backend.plans.models import Plan, PlanItem
from backend.reminders.models import ReminderSent
from backend.replies.models import AdviceReply
from backend.sessions import service as sessions
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.storage import StorageError, get_store
from backend.suggestions import service as suggestions
from backend.suggestions.models import Suggestion
from backend.users.models import User
from backend.voice.models import VoicePreference
from kinect_agent.analysis.document import read_if_readable

FORMAT_VERSION = "2"  # 2: metrics_earlier, settings.json, camera_sets.json, reminders.json
README = """Kinect Home Coach: all data held about patient {patient_id} ({email})
Made {made} (UTC) at the request of {who}. Archive format version {version}.

account.json      your account: e-mail, name, role, when it was made (no password: only its hash is kept,
                  and it is not given out)
therapists.json   the therapists assigned to you
plans.json        your exercise plans, each with its exercises, sets, repetitions and weekly frequency
sessions.json     every exercise session: when, which exercise, how long, the file's SHA-256, and the
                  metrics computed from it (repetitions, range of motion, balance, data quality ...) with the
                  version of the analysis that made them, and how each set felt to you ("feeling": pain 0-10,
                  effort 0-10 on the Borg CR10 scale, null = not answered or skipped)
sessions/         the session files themselves (.khs: raw and filtered skeleton, readable with the open-source
                  kinect-agent tool, docs/session-file.md); a file removed by the clinic's retention period, or
                  that could not be read, is listed in sessions.json with "file": null and the reason
                  "metrics_earlier": the documents a re-analysis replaced, each with its analysis version,
                  the SHA-256 and params of the session file it came from ("file": that file in sessions/,
                  session-ID-SHA.khs, when a re-analysis filtered the raw skeleton again into a new file)
advice.json       suggestions and messages from your therapists and from the system's rules; the advice of a
                  rule is in your language ("text", "locale"), written from what the rule found ("params"),
                  with the words it was first written in ("text_as_first_written")
replies.json      your replies to that advice, and when your therapist read them
devices.json      the home computers paired to your account
settings.json     your spoken-instructions setting and your consent to this computer's camera (null: none given)
camera_sets.json  the sets recorded with this computer's camera: when, which exercise, how they ended, the session
                  each became (the camera's landmark batches are kept only until the set ends)
reminders.json    the reminder e-mails sent to you: the plan, your local day and time, when sent, a failed delivery
audit.json        every recorded access to or change of your data: who, what, when, from which address

All times are UTC, ISO 8601. JSON files are UTF-8.
"""


def _earlier_file(z: zipfile.ZipFile, v: SessionMetricVersion, current_sha256: str) -> str | None:
    """Returns the archive's name of the session file a replaced document came from: the session's own file when it
    is the current one, else written once as sessions/session-ID-SHA12.khs; None when it is not kept (unknown,
    removed, or missing from the store)."""
    if not v.file_key or not v.file_hash:
        return None
    if v.file_hash == current_sha256:
        return f"sessions/session-{v.session_id}.khs"
    name = f"sessions/session-{v.session_id}-{v.file_hash[:12]}.khs"
    if name in z.namelist():
        return name
    try:
        z.writestr(name, get_store().get(v.file_key, v.file_hash))
    except StorageError:
        return None
    return name


def _iso(t: dt.datetime | None) -> str | None:
    return None if t is None else t.isoformat()


def _row(obj: object, names: tuple[str, ...]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for n in names:
        v = getattr(obj, n)
        out[n] = _iso(v) if isinstance(v, dt.datetime) else v.isoformat() if isinstance(v, dt.date) else v
    return out


def _advice(row: Suggestion, reader: Translator) -> dict[str, Any]:
    """Returns one piece of advice as the archive lists it: its columns, its text in the patient's language."""
    entry = _row(row, tuple(c.key for c in Suggestion.__table__.columns))
    entry["text"], entry["locale"] = suggestions.shown_text(row, reader)
    entry["text_as_first_written"] = row.text
    return entry


def _json(z: zipfile.ZipFile, name: str, data: Any) -> None:
    z.writestr(name, json.dumps(data, indent=2, ensure_ascii=False, default=str))


def build_archive(*, db_session: Session, patient: User, requested_by: str) -> IO[bytes]:
    """Returns a file (positioned at 0) holding the zip archive of everything about `patient` (README.txt inside).

    Session files are read from the object store, checked; one that cannot be read is listed with the reason.
    """
    pid = patient.id
    out = tempfile.SpooledTemporaryFile(max_size=64 * 1024 * 1024)
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr("README.txt", README.format(patient_id=pid, email=patient.email, who=requested_by,
                                               made=_iso(dt.datetime.now(dt.UTC)), version=FORMAT_VERSION))  # fmt: skip
        _json(z, "account.json", _row(patient, ("id", "email", "full_name", "role", "is_active", "created_at",
                                                "deactivated_at")))  # fmt: skip
        links = db_session.scalars(select(TherapistPatient).where(TherapistPatient.patient_id == pid)).all()
        therapists = []
        for link in links:
            t = db_session.get(User, link.therapist_id)
            therapists.append({"id": link.therapist_id, "full_name": t.full_name if t else None,
                               "email": t.email if t else None})  # fmt: skip
        _json(z, "therapists.json", therapists)
        plans = []
        for plan in db_session.scalars(select(Plan).where(Plan.patient_id == pid).order_by(Plan.id)):
            items = db_session.scalars(select(PlanItem).where(PlanItem.plan_id == plan.id).order_by(PlanItem.position))
            plans.append({
                **_row(plan, tuple(c.key for c in Plan.__table__.columns)),
                "items": [_row(i, tuple(c.key for c in PlanItem.__table__.columns)) for i in items],
            })  # fmt: skip
        _json(z, "plans.json", plans)
        earlier: dict[int, list[dict[str, Any]]] = {}
        for v, current in db_session.execute(
            select(SessionMetricVersion, ExerciseSession.content_hash)
            .join(ExerciseSession, ExerciseSession.id == SessionMetricVersion.session_id)
            .where(ExerciseSession.patient_id == pid)
            .order_by(SessionMetricVersion.id)
        ).all():
            earlier.setdefault(v.session_id, []).append(
                {"analysis_version": v.analysis_version, "replaced_at": _iso(v.replaced_at), "document": v.document,
                 "file_sha256": v.file_hash, "processing_params": v.processing_params,
                 "file": _earlier_file(z, v, current)}
            )  # fmt: skip
        listed = []
        rows = db_session.execute(
            select(ExerciseSession, Exercise.slug, SessionMetric.document, SessionFeeling)
            .outerjoin(Exercise, Exercise.id == ExerciseSession.exercise_id)
            .outerjoin(SessionMetric, SessionMetric.session_id == ExerciseSession.id)
            .outerjoin(SessionFeeling, SessionFeeling.session_id == ExerciseSession.id)
            .where(ExerciseSession.patient_id == pid)
            .order_by(ExerciseSession.started_at, ExerciseSession.id)
        ).all()
        for s, slug, doc, felt in rows:
            entry = _row(s, ("id", "client_session_id", "started_at", "duration_s", "n_frames", "file_format",
                             "file_size", "content_hash", "processing_version", "processing_params", "status",
                             "error", "created_at"))  # fmt: skip
            entry["client_session_id"] = str(s.client_session_id)
            entry["exercise"] = slug
            readable = read_if_readable(doc)  # today's schema; a document no schema reads is kept as stored
            entry["metrics"] = readable.model_dump(mode="json") if readable is not None else doc
            entry["metrics_earlier"] = earlier.get(s.id, [])
            entry["feeling"] = None if felt is None else {
                "pain_nrs": felt.pain_nrs, "effort_borg_cr10": felt.effort_cr10, "answered_at": _iso(felt.updated_at)
            }  # fmt: skip
            try:
                data = sessions.session_file(db_session=db_session, session_id=s.id)
                name = f"sessions/session-{s.id}.khs"
                z.writestr(name, data)
                entry["file"], entry["file_missing_reason"] = name, None
            except (StorageError, SessionFileRemoved) as exc:
                entry["file"], entry["file_missing_reason"] = None, exc.message
            listed.append(entry)
        _json(z, "sessions.json", listed)
        reader = translator(patient.locale)
        advice = db_session.scalars(select(Suggestion).where(Suggestion.patient_id == pid).order_by(Suggestion.id))
        _json(z, "advice.json", [_advice(a, reader) for a in advice])
        replies = db_session.scalars(select(AdviceReply).where(AdviceReply.patient_id == pid).order_by(AdviceReply.id))
        _json(z, "replies.json", [_row(r, tuple(c.key for c in AdviceReply.__table__.columns)) for r in replies])
        devices = db_session.scalars(select(Device).where(Device.patient_id == pid).order_by(Device.id))
        _json(z, "devices.json", [_row(d, ("id", "name", "created_at")) for d in devices])
        voice, consent = db_session.get(VoicePreference, pid), db_session.get(CameraConsent, pid)
        _json(z, "settings.json", {
            "voice": None if voice is None else _row(voice, ("enabled", "volume", "updated_at")),
            "camera_consent": None if consent is None else _row(consent, ("consent_version", "given_at")),
        })  # fmt: skip
        sets = db_session.execute(
            select(CameraSet, Exercise.slug)
            .outerjoin(Exercise, Exercise.id == CameraSet.exercise_id)
            .where(CameraSet.patient_id == pid)
            .order_by(CameraSet.started_at)
        ).all()
        _json(z, "camera_sets.json", [
            {**_row(c, ("started_at", "ended_at", "status", "end_reason", "target_reps", "n_frames", "session_id",
                        "error")), "id": str(c.id), "exercise": slug}
            for c, slug in sets
        ])  # fmt: skip
        sent = db_session.scalars(select(ReminderSent).where(ReminderSent.patient_id == pid).order_by(ReminderSent.id))
        _json(z, "reminders.json", [_row(r, ("plan_id", "local_date", "local_time", "due_at", "sent_at", "error"))
                                    for r in sent])  # fmt: skip
        audit = db_session.scalars(
            select(AuditEvent)
            .where(or_(AuditEvent.patient_id == pid, AuditEvent.actor_user_id == pid))
            .order_by(AuditEvent.at, AuditEvent.id)
        )
        _json(z, "audit.json", [_row(a, tuple(c.key for c in AuditEvent.__table__.columns)) for a in audit])
    out.seek(0)
    return out
