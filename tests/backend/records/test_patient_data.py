"""A patient's whole data in one archive, erasure that leaves nothing behind, and the retention period."""

from __future__ import annotations

import datetime as dt
import io
import json
import zipfile

import sqlalchemy as sa

from backend.audit.models import AuditEvent
from backend.database import Base
from backend.records.retention import apply_retention
from backend.sessions.models import ExerciseSession, SessionDetail, SessionMetric
from tests.backend.khs_files import make_khs


def _upload(client, headers, seed):
    response = client.post("/api/v1/sessions", content=make_khs("squat", 1, seed=seed),
                           headers={"Content-Type": "application/octet-stream", **headers},
                           params={"exercise": "squat"})  # fmt: skip
    assert response.status_code == 201, response.text
    return response.json()["id"]


def _patient_with_data(client, make_patient_with_therapist, auth_headers, seed, run_jobs):
    patient, therapist = make_patient_with_therapist()
    headers = auth_headers(patient)
    ids = [_upload(client, headers, seed), _upload(client, headers, seed + 1)]
    assert client.get(f"/api/v1/sessions/{ids[0]}/replay", headers=headers).status_code == 202
    assert run_jobs() == 3  # a worker builds the replay and the two sessions' details
    assert client.get(f"/api/v1/sessions/{ids[0]}/replay", headers=headers).status_code == 200
    plan = {"title": "knees", "start_date": "2026-11-23",
            "items": [{"exercise_slug": "squat", "sets": 1, "repetitions": 5, "frequency_per_week": 2}]}  # fmt: skip
    th = auth_headers(therapist)
    assert client.post(f"/api/v1/patients/{patient.id}/plans", json=plan, headers=th).status_code == 201
    advice = client.post(f"/api/v1/patients/{patient.id}/suggestions", json={"text": "Slower."}, headers=th)
    assert advice.is_success
    reply = {"suggestion_id": advice.json()["id"], "preset": "hurt", "text": "My knee"}
    assert client.post(f"/api/v1/patients/{patient.id}/replies", json=reply, headers=headers).status_code == 201
    assert client.post(f"/api/v1/patients/{patient.id}/pairing-codes", headers=headers).is_success
    return patient, ids


def test_the_archive_holds_everything_with_a_readme(
    fetch_archive, client, make_patient_with_therapist, auth_headers, with_store, run_jobs
):
    patient, ids = _patient_with_data(client, make_patient_with_therapist, auth_headers, seed=51, run_jobs=run_jobs)
    response = fetch_archive(patient.id, auth_headers(patient))
    assert response.status_code == 200 and response.headers["content-type"] == "application/zip"
    z = zipfile.ZipFile(io.BytesIO(response.content))
    names = set(z.namelist())
    assert {"README.txt", "account.json", "plans.json", "sessions.json", "advice.json", "audit.json"} <= names
    assert f"patient {patient.id} ({patient.email})" in z.read("README.txt").decode()
    sessions = json.loads(z.read("sessions.json"))
    assert [s["id"] for s in sessions] == sorted(ids) and all(s["metrics"]["repetitions"] >= 0 for s in sessions)
    for s in sessions:
        data = z.read(s["file"])
        assert with_store.get(f"session/{s['content_hash'][:2]}/{s['content_hash']}", s["content_hash"]) == data
    assert json.loads(z.read("account.json"))["email"] == patient.email
    assert "password_hash" not in z.read("account.json").decode()
    assert json.loads(z.read("plans.json"))[0]["items"][0]["repetitions"] == 5
    assert json.loads(z.read("advice.json"))[-1]["text"] == "Slower."
    reply = json.loads(z.read("replies.json"))[-1]
    assert (reply["preset"], reply["text"], reply["read_at"]) == ("hurt", "My knee", None)
    assert any(a["action"] == "session.create" or a["action"].startswith("session") for a in
               json.loads(z.read("audit.json")))  # fmt: skip


def _mentions(db_session, patient_id: int, email: str, session_ids: list[int]) -> list[str]:
    """Returns every row of every table that names the patient: an id column, a session of theirs, the e-mail."""
    found = []
    conn = db_session.connection()
    for table in Base.metadata.sorted_tables:
        for row in conn.execute(sa.select(table)).mappings():
            for col, value in row.items():
                if (
                    col
                    in (
                        "patient_id",
                        "user_id",
                        "actor_user_id",
                        "author_id",
                        "decided_by_id",
                        "created_by_id",
                        "therapist_id",
                    )
                    and value == patient_id
                    and table.name != "therapist_patient"
                ):
                    found.append(f"{table.name}.{col}")
                elif table.name == "user" and col == "id" and value == patient_id:
                    found.append("user.id")
                elif col == "session_id" and value in session_ids:
                    found.append(f"{table.name}.session_id")
                elif table.name == "job" and col == "payload" and (value or {}).get("session_id") in session_ids:
                    found.append("job.payload names a session of theirs")
                elif email.lower() in json.dumps(value, default=str).lower():
                    found.append(f"{table.name}.{col} holds the e-mail")
        if table.name == "therapist_patient":
            n = conn.scalar(sa.select(sa.func.count()).select_from(table).where(table.c.patient_id == patient_id))
            found += ["therapist_patient.patient_id"] * n
    return found


def test_erasure_leaves_only_an_audit_entry(
    fetch_archive, client, db_session, make_patient_with_therapist, make_user, auth_headers, with_store, run_jobs
):
    patient, ids = _patient_with_data(client, make_patient_with_therapist, auth_headers, seed=61, run_jobs=run_jobs)
    other, other_ids = _patient_with_data(client, make_patient_with_therapist, auth_headers, seed=71, run_jobs=run_jobs)
    admin = make_user("admin")
    headers = auth_headers(admin)
    assert fetch_archive(patient.id, headers).status_code == 200
    kept = {k for k in with_store.keys()}
    others = set(db_session.scalars(sa.select(ExerciseSession.file_key).where(ExerciseSession.id.in_(other_ids))))
    pid, email = patient.id, patient.email
    wrong = client.post(f"/api/v1/patients/{pid}/erasure", json={"confirm_email": "x@y.org"}, headers=headers)
    assert wrong.status_code == 422 and wrong.json()["error"] == "InvalidInput"
    assert set(with_store.keys()) == kept
    response = client.post(f"/api/v1/patients/{pid}/erasure", json={"confirm_email": email.upper()}, headers=headers)
    assert response.status_code == 200, response.text
    # 2 files, 1 replay, 2 details, the archive
    assert response.json()["rows"]["exercise_session"] == 2 and response.json()["objects"] == 6
    assert response.json()["rows"]["patient_archive"] == 1
    assert response.json()["rows"]["advice_reply"] == 1
    db_session.expire_all()
    assert _mentions(db_session, pid, email, ids) == []
    assert others <= set(with_store.keys()) and len(set(with_store.keys())) == len(kept) - 6
    events = db_session.scalars(sa.select(AuditEvent).where(AuditEvent.action == "patient.erase")).all()
    assert len(events) == 1 and events[0].actor_user_id == admin.id and events[0].patient_id is None
    assert fetch_archive(other.id, headers).status_code == 200


def test_retention_removes_old_files_and_keeps_metrics(client, db_session, make_patient_with_therapist, auth_headers,
                                                       with_store, run_jobs):  # fmt: skip
    patient, ids = _patient_with_data(client, make_patient_with_therapist, auth_headers, seed=81, run_jobs=run_jobs)
    old = db_session.get(ExerciseSession, ids[0])
    old.started_at = dt.datetime(2025, 1, 1, tzinfo=dt.UTC)
    db_session.flush()
    key = old.file_key
    detail_key = db_session.scalar(sa.select(SessionDetail.data_key).where(SessionDetail.session_id == ids[0]))
    assert with_store.exists(detail_key)
    report = apply_retention(db_session=db_session, days=365, now=dt.datetime(2026, 11, 27, tzinfo=dt.UTC))
    db_session.commit()
    assert report.per_patient == {patient.id: 1} and not with_store.exists(key)
    assert not with_store.exists(detail_key), "the curves of a removed recording go with it"
    assert db_session.scalar(sa.select(SessionDetail.id).where(SessionDetail.session_id == ids[0])) is None
    db_session.expire_all()
    assert db_session.get(ExerciseSession, ids[0]).file_key is None
    assert db_session.scalar(sa.select(SessionMetric.repetitions).where(SessionMetric.session_id == ids[0])) is not None
    response = client.get(f"/api/v1/sessions/{ids[0]}/file", headers=auth_headers(patient))
    assert response.status_code == 410 and response.json()["error"] == "SessionFileRemoved"
    assert client.get(f"/api/v1/sessions/{ids[1]}/file", headers=auth_headers(patient)).status_code == 200
    audit = db_session.scalars(sa.select(AuditEvent).where(AuditEvent.action == "session.files_expired")).one()
    assert audit.patient_id == patient.id and audit.detail["files"] == 1


def test_the_archive_says_how_each_set_felt(fetch_archive, client, make_user, auth_headers, with_store):
    patient = make_user("patient")
    headers = auth_headers(patient)
    answered, unanswered = _upload(client, headers, 61), _upload(client, headers, 62)
    r = client.put(f"/api/v1/sessions/{answered}/feeling", json={"pain": 3, "effort": 5.5}, headers=headers)
    assert r.status_code == 200, r.text
    z = zipfile.ZipFile(io.BytesIO(fetch_archive(patient.id, headers).content))
    by_id = {s["id"]: s for s in json.loads(z.read("sessions.json"))}
    felt = by_id[answered]["feeling"]
    assert (felt["pain_nrs"], felt["effort_borg_cr10"]) == (3, 5.5) and felt["answered_at"], felt
    assert by_id[unanswered]["feeling"] is None
    assert "Borg CR10" in z.read("README.txt").decode()


def test_the_archive_holds_replaced_metrics_settings_camera_sets_and_reminders(
    fetch_archive, client, db_session, make_user, auth_headers
):
    from backend.camera.models import CameraConsent
    from backend.jobs.models import SessionMetricVersion
    from backend.voice.models import VoicePreference

    patient = make_user("patient")
    headers = auth_headers(patient)
    sid = _upload(client, headers, 63)
    db_session.add(SessionMetricVersion(session_id=sid, analysis_version="before 2026.11.27",
                                        document={"repetitions": 2, "rom_deg": 1.0}))  # fmt: skip
    db_session.add(VoicePreference(patient_id=patient.id, enabled=False, volume=0.4))
    db_session.add(CameraConsent(patient_id=patient.id, consent_version="1"))
    db_session.commit()
    z = zipfile.ZipFile(io.BytesIO(fetch_archive(patient.id, headers).content))
    (session,) = json.loads(z.read("sessions.json"))
    assert [(m["analysis_version"], m["document"]["rom_deg"]) for m in session["metrics_earlier"]] == [
        ("before 2026.11.27", 1.0)
    ]
    settings = json.loads(z.read("settings.json"))
    assert (settings["voice"]["enabled"], settings["voice"]["volume"]) == (False, 0.4)
    assert settings["camera_consent"]["consent_version"] == "1" and settings["camera_consent"]["given_at"]
    assert json.loads(z.read("camera_sets.json")) == [] and json.loads(z.read("reminders.json")) == []
    readme = z.read("README.txt").decode()
    assert all(name in readme for name in ("metrics_earlier", "settings.json", "camera_sets.json", "reminders.json"))
    assert "Archive format version 3" in readme


def test_the_archive_writes_the_analysis_reasons_in_the_patients_language(
    fetch_archive, client, db_session, make_user, auth_headers, exercise, store
):
    import datetime as dt
    from pathlib import Path

    documents = Path(__file__).parents[2] / "kinect_agent" / "analysis" / "documents"
    english = json.loads((documents / "schema2.json").read_text(encoding="utf-8"))  # before reason ids
    english["quality"] |= {"ok": False, "reasons": ["the measured positions have gaps", "an older analysis's words"]}
    patient = make_user("patient")
    patient.locale = "es"
    store(patient, exercise, dt.datetime(2026, 11, 2, 9, 0, tzinfo=dt.UTC), doc=english)
    db_session.flush()
    response = fetch_archive(patient.id, auth_headers(patient))
    assert response.status_code == 200, response.text
    (session,) = json.loads(zipfile.ZipFile(io.BytesIO(response.content)).read("sessions.json"))
    assert session["metrics"]["quality"]["reasons"] == [
        {"id": "gaps", "params": {}, "text": "faltan datos en las posiciones medidas"},
        {"id": None, "params": {}, "text": "an older analysis's words"},
    ]
    withheld = session["metrics"]["range_of_motion_95_withheld"]["shoulder_abduction_L"]
    assert withheld["id"] == "too_uncertain" and "218°" in withheld["text"] and "abarcaría" in withheld["text"]
