"""Everything the clinic holds about one patient, in one zip archive with a README inside."""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import tempfile
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import IO, Any

from sqlalchemy import or_, select
from sqlalchemy.orm import Session

from backend.audit.models import AuditEvent
from backend.camera.models import CameraConsent, CameraSet
from backend.config import Settings
from backend.devices.models import Device
from backend.exceptions import InvalidSessionFile, SessionFileRemoved
from backend.exercises.models import Exercise
from backend.feeling.models import SessionFeeling
from backend.i18n import Translator, translator
from backend.jobs.listing import error_words
from backend.jobs.models import SessionMetricVersion
from backend.patients.models import TherapistPatient
from backend.plans.models import Plan, PlanItem
from backend.reminders.models import ReminderSent
from backend.replies.models import AdviceReply
from backend.session_texts import reasons
from backend.sessions import prepared_export
from backend.sessions import service as sessions
from backend.sessions.export import SessionExports, export_context, session_exports
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.storage import StorageError, get_store
from backend.suggestions import service as suggestions
from backend.suggestions.models import Suggestion
from backend.users.models import User
from backend.voice.models import VoicePreference
from kinect_agent.analysis.document import read_if_readable
from kinect_agent.export.files import ExportFile

FORMAT_VERSION = "3"  # 2: metrics_earlier, settings.json, camera_sets.json, reminders.json; 3: exports/, manifest.json
# The exports of each session in the archive: the data tables and the health record. Not trc, bvh: they re-encode
# the skeleton the .khs file already holds, for motion software, and would add 1.7-1.9 s of CPU and 2.1-2.2 MB (4 times
# the .khs) per 4.5-minute session (bench/README.md); the session page still downloads them.
EXPORT_FORMATS = ("csv", "fhir")
# The zip is written to a temporary file kept in memory up to this size, on disk beyond it: a build holds one member
# at a time (a session file, an export, a JSON list), however many sessions the archive has (bench/README.md).
SPOOL_MAX_BYTES = 2 * 1024 * 1024
README = """Kinect Home Coach: all data held about patient {patient_id} ({email})
Made {made} (UTC) at the request of {who}. Archive format version {version}.

account.json      your account: e-mail, name, role, when it was made (no password: only its hash is kept,
                  and it is not given out)
therapists.json   the therapists assigned to you
plans.json        your exercise plans, each with its exercises, sets, repetitions and weekly frequency
sessions.json     every exercise session: when, which exercise, how long, the file's SHA-256, and the
                  metrics computed from it (repetitions, range of motion, balance, data quality ...) with the
                  version of the analysis that made them, and how each set felt to you ("feeling": pain 0-10,
                  effort 0-10 on the Borg CR10 scale, null = not answered or skipped); each reason the
                  analysis gives (why data quality was poor, an interval withheld, balance not measured) has
                  its "text" in your language, and its "id" and numbers ("params")
                  "metrics_earlier": the documents a re-analysis replaced, each with its analysis version,
                  the SHA-256 and params of the session file it came from ("file": that file in sessions/,
                  session-ID-SHA.khs, when a re-analysis filtered the raw skeleton again into a new file)
sessions/         the session files themselves (.khs: raw and filtered skeleton, readable with the open-source
                  kinect-agent tool, docs/session-file.md); a file removed by the clinic's retention period, or
                  that could not be read, is listed in sessions.json with "file": null and the reason
exports/session-N/  each session in the formats other software reads, as the session page downloads them
                  (sessions.json "exports" names them, "exports_missing" says why one is not there):
  session-N-csv.zip    tables a spreadsheet opens: metrics.csv, repetitions.csv, feeling.csv, recording.csv,
                       angles_raw.csv and angles_filtered.csv (joint angles per frame, degrees)
  session-N-fhir.json  an HL7 FHIR R4 Bundle of Observations (duration, repetitions, range of motion,
                       indicators, pain and effort) for a health record
                  (the OpenSim and animation files, .trc and .bvh, are made from the .khs file by the
                  session page's downloads or `kinect-agent export`)
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

manifest.json     every file of this archive with its size and SHA-256 (to check the copy is whole), and per
                  session its file, its exports and what could not be given

All times are UTC, ISO 8601. JSON files are UTF-8.
{problems}"""
PROBLEMS = """
Sessions not complete in this archive ({n}): their metrics are in sessions.json, but the file or an export
could not be given; ask the clinic about them (their staff check stored files with `coach-server storage check`).
{lines}
"""


_PATIENT_ENGLISH = Translator("en")  # the archive's README and files are in English


def _earlier_file(out: _Zip, v: SessionMetricVersion, current_sha256: str) -> str | None:
    """Returns the archive's name of the session file a replaced document came from: the session's own file when it
    is the current one, else written once as sessions/session-ID-SHA12.khs; None when it is not kept (unknown,
    removed, or missing from the store)."""
    if not v.file_key or not v.file_hash:
        return None
    if v.file_hash == current_sha256:
        return f"sessions/session-{v.session_id}.khs"
    name = f"sessions/session-{v.session_id}-{v.file_hash[:12]}.khs"
    if name in out.z.namelist():
        return name
    try:
        out.add(name, get_store().get(v.file_key, v.file_hash))
    except StorageError:
        return None
    return name


def _said_to_patient(exc: StorageError | SessionFileRemoved) -> str:
    """Returns why a session's file is not in the archive, as one sentence for its reader (the patient): never the
    store's own words, which name its folder or bucket (those stay in the server's log and `storage check`)."""
    return error_words(f"{type(exc).__name__}: {exc.message}", _PATIENT_ENGLISH) or ""


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


@dataclass
class _Zip:
    """The archive being written: each member's size and SHA-256 kept for manifest.json."""

    z: zipfile.ZipFile
    members: list[dict[str, Any]] = field(default_factory=list)

    def add(self, name: str, data: bytes | str) -> None:
        """Writes one member and notes its size and SHA-256."""
        raw = data.encode("utf-8") if isinstance(data, str) else data
        self.z.writestr(name, raw)
        self.members.append({"name": name, "size": len(raw), "sha256": hashlib.sha256(raw).hexdigest()})

    def json(self, name: str, data: Any) -> None:
        """Writes one JSON member (UTF-8, indented)."""
        self.add(name, json.dumps(data, indent=2, ensure_ascii=False, default=str))


@dataclass(frozen=True)
class Archive:
    """A built archive: `file` (a zip positioned at 0, on disk past SPOOL_MAX_BYTES; the caller closes it), how many
    sessions it holds, and those
    it holds incomplete, each with what is missing and why (`incomplete`: session id -> reasons, also in README.txt
    and manifest.json)."""

    file: IO[bytes]
    sessions: int
    incomplete: dict[int, list[str]]


Progress = Callable[[int, int], None]  # (sessions written, sessions in all), called before each session and at the end


def _exports(
    db_session: Session, session_id: int, settings: Settings, file: bytes | None, lost: str | None
) -> SessionExports:
    """Returns a session's exports in EXPORT_FORMATS and why any is missing. One stored for today's inputs is read
    from the object store (sha256 checked); the others are built from its file (`file`, read and checked by the
    caller; None when it could not be, `lost` saying why), a long recording's too: the archive is built by a
    job-queue worker or the admin's command, never in a request (backend.records.prepared_archive)."""
    row = sessions.get_session_row(db_session=db_session, session_id=session_id)
    context = export_context(db_session=db_session, row=row)
    files: dict[str, ExportFile] = {}
    for fmt in EXPORT_FORMATS:
        try:
            found = prepared_export.stored_for_today(db_session=db_session, row=row, fmt=fmt, context=context)
        except StorageError:
            found = None  # a lost or damaged stored export is made again
        if found is not None:
            files[fmt] = ExportFile(found.data(), found.media_type, found.file_name)
    wanted = tuple(f for f in EXPORT_FORMATS if f not in files)
    if not wanted:
        return SessionExports(files, {})
    if file is None:
        return SessionExports(files, dict.fromkeys(wanted, f"the session file could not be read: {lost}"))
    try:
        built = session_exports(db_session=db_session, row=row, formats=wanted, max_frames=settings.SESSION_MAX_FRAMES,
                                max_decoded_bytes=settings.SESSION_MAX_DECODED_BYTES, context=context,
                                data=file)  # fmt: skip
    except InvalidSessionFile as exc:
        return SessionExports(files, dict.fromkeys(wanted, exc.message))
    return SessionExports(files | built.files, built.unavailable)


def _sessions(
    db_session: Session, pid: int, out: _Zip, settings: Settings, reader: Translator, progress: Progress
) -> tuple[list[dict[str, Any]], dict[int, list[str]]]:
    """Writes every session's file and exports; returns sessions.json's entries (the metrics' reasons in the
    reader's language: backend.session_texts.reasons) and the incomplete sessions."""
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
             "file": _earlier_file(out, v, current)}
        )  # fmt: skip
    listed: list[dict[str, Any]] = []
    incomplete: dict[int, list[str]] = {}
    rows = db_session.execute(
        select(ExerciseSession, Exercise.slug, SessionMetric.document, SessionFeeling)
        .outerjoin(Exercise, Exercise.id == ExerciseSession.exercise_id)
        .outerjoin(SessionMetric, SessionMetric.session_id == ExerciseSession.id)
        .outerjoin(SessionFeeling, SessionFeeling.session_id == ExerciseSession.id)
        .where(ExerciseSession.patient_id == pid)
        .order_by(ExerciseSession.started_at, ExerciseSession.id)
    ).all()
    for n, (s, slug, doc, felt) in enumerate(rows):
        progress(n, len(rows))
        entry = _row(s, ("id", "client_session_id", "started_at", "duration_s", "n_frames", "file_format",
                         "file_size", "content_hash", "processing_version", "processing_params", "status",
                         "error", "created_at"))  # fmt: skip
        entry["client_session_id"] = str(s.client_session_id)
        entry["exercise"] = slug
        readable = read_if_readable(doc)  # today's schema; a document no schema reads is kept as stored
        entry["metrics"] = doc if readable is None else reasons.with_texts(readable, reader).model_dump(mode="json")
        entry["metrics_earlier"] = earlier.get(s.id, [])
        entry["feeling"] = None if felt is None else {
            "pain_nrs": felt.pain_nrs, "effort_borg_cr10": felt.effort_cr10, "answered_at": _iso(felt.updated_at)
        }  # fmt: skip
        problems = []
        data: bytes | None = None
        try:
            data = sessions.session_file(db_session=db_session, session_id=s.id)
            name = f"sessions/session-{s.id}.khs"
            out.add(name, data)
            entry["file"], entry["file_missing_reason"] = name, None
        except (StorageError, SessionFileRemoved) as exc:
            entry["file"], entry["file_missing_reason"] = None, _said_to_patient(exc)
            problems.append(f"file: {entry['file_missing_reason']}")
        made = _exports(db_session, s.id, settings, data, entry["file_missing_reason"])
        entry["exports"] = {}
        for fmt, file in made.files.items():
            entry["exports"][fmt] = name = f"exports/session-{s.id}/{file.file_name}"
            out.add(name, file.data)
        entry["exports_missing"] = made.unavailable
        problems += [f"{fmt}: {why}" for fmt, why in made.unavailable.items() if data is not None]
        if problems:
            incomplete[s.id] = problems
        listed.append(entry)
    progress(len(rows), len(rows))
    return listed, incomplete


def build_archive(
    *,
    db_session: Session,
    patient: User,
    requested_by: str,
    settings: Settings,
    progress: Progress = lambda done, total: None,
    made_at: dt.datetime | None = None,
) -> Archive:
    """Returns the zip archive of everything about `patient` (README.txt and manifest.json inside).

    Session files are read from the object store, checked; each session is exported in EXPORT_FORMATS. A session
    whose file is missing, corrupt or removed, or that cannot give an export (e.g. fhir without metrics), does not
    stop the archive: its metrics are still in it, and it is named with the reason in sessions.json, README.txt,
    manifest.json and Archive.incomplete. Minutes of CPU for years of sessions: called by a job-queue worker
    (backend.records.prepared_archive) and the admin's command, never in a request. settings: the limits a session
    file is decoded within; progress(done, total): told before each session and at the end; made_at: the time
    the README and manifest give (default now).
    """
    pid = patient.id
    made = _iso(made_at or dt.datetime.now(dt.UTC))
    tmp = tempfile.SpooledTemporaryFile(max_size=SPOOL_MAX_BYTES)
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as z:
        out = _Zip(z)
        out.json("account.json", _row(patient, ("id", "email", "full_name", "role", "is_active", "created_at",
                                                "deactivated_at")))  # fmt: skip
        links = db_session.scalars(select(TherapistPatient).where(TherapistPatient.patient_id == pid)).all()
        therapists = []
        for link in links:
            t = db_session.get(User, link.therapist_id)
            therapists.append({"id": link.therapist_id, "full_name": t.full_name if t else None,
                               "email": t.email if t else None})  # fmt: skip
        out.json("therapists.json", therapists)
        plans = []
        for plan in db_session.scalars(select(Plan).where(Plan.patient_id == pid).order_by(Plan.id)):
            items = db_session.scalars(select(PlanItem).where(PlanItem.plan_id == plan.id).order_by(PlanItem.position))
            plans.append({
                **_row(plan, tuple(c.key for c in Plan.__table__.columns)),
                "items": [_row(i, tuple(c.key for c in PlanItem.__table__.columns)) for i in items],
            })  # fmt: skip
        out.json("plans.json", plans)
        reader = translator(patient.locale)
        listed, incomplete = _sessions(db_session, pid, out, settings, reader, progress)
        out.json("sessions.json", listed)
        advice = db_session.scalars(select(Suggestion).where(Suggestion.patient_id == pid).order_by(Suggestion.id))
        out.json("advice.json", [_advice(a, reader) for a in advice])
        replies = db_session.scalars(select(AdviceReply).where(AdviceReply.patient_id == pid).order_by(AdviceReply.id))
        out.json("replies.json", [_row(r, tuple(c.key for c in AdviceReply.__table__.columns)) for r in replies])
        devices = db_session.scalars(select(Device).where(Device.patient_id == pid).order_by(Device.id))
        out.json("devices.json", [_row(d, ("id", "name", "created_at")) for d in devices])
        voice, consent = db_session.get(VoicePreference, pid), db_session.get(CameraConsent, pid)
        out.json("settings.json", {
            "voice": None if voice is None else _row(voice, ("enabled", "volume", "updated_at")),
            "camera_consent": None if consent is None else _row(consent, ("consent_version", "given_at")),
        })  # fmt: skip
        sets = db_session.execute(
            select(CameraSet, Exercise.slug)
            .outerjoin(Exercise, Exercise.id == CameraSet.exercise_id)
            .where(CameraSet.patient_id == pid)
            .order_by(CameraSet.started_at)
        ).all()
        out.json("camera_sets.json", [
            {**_row(c, ("started_at", "ended_at", "status", "end_reason", "target_reps", "n_frames", "session_id",
                        "error")), "id": str(c.id), "exercise": slug}
            for c, slug in sets
        ])  # fmt: skip
        sent = db_session.scalars(select(ReminderSent).where(ReminderSent.patient_id == pid).order_by(ReminderSent.id))
        out.json("reminders.json", [_row(r, ("plan_id", "local_date", "local_time", "due_at", "sent_at", "error"))
                                    for r in sent])  # fmt: skip
        audit = db_session.scalars(
            select(AuditEvent)
            .where(or_(AuditEvent.patient_id == pid, AuditEvent.actor_user_id == pid))
            .order_by(AuditEvent.at, AuditEvent.id)
        )
        out.json("audit.json", [_row(a, tuple(c.key for c in AuditEvent.__table__.columns)) for a in audit])
        problems = "" if not incomplete else PROBLEMS.format(n=len(incomplete), lines="\n".join(
            f"  session {sid}: {'; '.join(why)}" for sid, why in incomplete.items()))  # fmt: skip
        out.add("README.txt", README.format(patient_id=pid, email=patient.email, who=requested_by, made=made,
                                            version=FORMAT_VERSION, problems=problems))  # fmt: skip
        z.writestr("manifest.json", json.dumps({
            "format_version": FORMAT_VERSION, "patient_id": pid, "made": made, "files": out.members,
            "sessions": [{"id": e["id"], "file": e["file"], "file_missing_reason": e["file_missing_reason"],
                          "exports": e["exports"], "exports_missing": e["exports_missing"]} for e in listed],
            "incomplete_sessions": [{"id": sid, "reasons": why} for sid, why in incomplete.items()],
        }, indent=2, ensure_ascii=False))  # fmt: skip
    tmp.seek(0)
    return Archive(tmp, len(listed), incomplete)
