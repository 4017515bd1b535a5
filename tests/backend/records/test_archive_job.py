"""The patient's archive is made by a job-queue worker, never in the request: asked (202 and where it is), made once
however often it is asked, kept in the object store and downloaded behind the same rules as before (the patient, or
an admin); a new session makes it stale; a failed build is said; erasure deletes it."""

from __future__ import annotations

import datetime as dt
import io
import tracemalloc
import zipfile

import numpy as np
import pytest
import sqlalchemy as sa

from backend.i18n import ENGLISH
from backend.jobs.models import Job
from backend.jobs.queue import LEASE
from backend.records import prepared_archive
from backend.records.archive import build_archive
from backend.records.models import PatientArchive
from backend.records.retention import apply_retention
from backend.sessions.models import ExerciseSession
from backend.storage import factory, get_store
from backend.storage.check import check
from tests.backend.object_stores import local_store
from tests.backend.records.test_patient_data import _upload
from tests.backend.session_rows import store_session


def _count(db_session, model, *where) -> int:
    return db_session.scalar(sa.select(sa.func.count()).select_from(model).where(*where))


def _archive_keys(store) -> list[str]:
    return sorted(k for k in store.keys() if k.startswith("archive/"))


@pytest.fixture
def patient_with_sessions(client, make_patient_with_therapist, auth_headers, run_jobs):
    """(patient, therapist, patient's headers, session ids): two uploaded sessions, their details built."""
    patient, therapist = make_patient_with_therapist()
    headers = auth_headers(patient)
    ids = [_upload(client, headers, 301), _upload(client, headers, 302)]
    assert run_jobs() == 2
    return patient, therapist, headers, ids


def test_asking_answers_202_and_the_worker_makes_it_once(
    client, db_session, run_jobs, with_store, patient_with_sessions, settings
):
    patient, _, headers, ids = patient_with_sessions
    base = f"/api/v1/patients/{patient.id}/archive"
    assert client.get(f"{base}/status", headers=headers).json()["state"] == "none"
    asked = client.post(base, headers=headers)
    assert asked.status_code == 202, asked.text
    body = asked.json()
    assert body["state"] == "preparing" and "queued" in body["detail"] and body["download_url"] is None
    assert body["status_url"] == f"{base}/status" and asked.headers["location"] == body["status_url"]
    assert asked.headers["retry-after"] == "3"
    for again in (client.post(base, headers=headers), client.get(base, headers=headers)):
        assert again.status_code == 202 and again.json()["state"] == "preparing"
    assert _count(db_session, Job, Job.kind == "archive") == 1, "asked three times, queued once"
    assert _count(db_session, PatientArchive) == 0 and _archive_keys(with_store) == [], "nothing built in a request"
    assert run_jobs() == 1
    status = client.get(f"{base}/status", headers=headers).json()
    assert status["state"] == "ready" and status["current"] and status["sessions"] == 2, status
    assert status["download_url"].startswith(f"{base}?sha256=") and status["incomplete"] == 0
    assert client.post(base, headers=headers).status_code == 200, "a kept archive of today's data: nothing queued"
    assert run_jobs() == 0
    got = client.get(status["download_url"], headers=headers)
    assert got.status_code == 200 and got.headers["content-type"] == "application/zip"
    kept = db_session.scalar(sa.select(PatientArchive))
    assert got.content == with_store.get(kept.data_key, kept.data_hash) and kept.size == len(got.content)
    assert got.headers["content-disposition"] == f'attachment; filename="{kept.file_name}"'
    assert client.get(base, headers=headers).content == got.content, "without sha256: the same current archive"
    # the content equals an archive built directly from the same data at the same time (the audit log aside: the
    # download added to it since)
    direct = build_archive(db_session=db_session, patient=patient, requested_by="the patient", settings=settings,
                           made_at=kept.made_at)  # fmt: skip
    made, expected = zipfile.ZipFile(io.BytesIO(got.content)), zipfile.ZipFile(direct.file)
    assert made.namelist() == expected.namelist()
    for name in expected.namelist():
        if name not in ("audit.json", "manifest.json") and not name.endswith("fhir.json"):  # fhir: fresh uuids
            assert made.read(name) == expected.read(name), name
    assert {f"sessions/session-{i}.khs" for i in ids} <= set(made.namelist())


def test_a_new_session_makes_the_kept_archive_stale_and_a_new_one_replaces_it(
    client, db_session, run_jobs, with_store, patient_with_sessions
):
    patient, _, headers, _ = patient_with_sessions
    base = f"/api/v1/patients/{patient.id}/archive"
    assert client.post(base, headers=headers).status_code == 202 and run_jobs() == 1
    first = client.get(f"{base}/status", headers=headers).json()
    old = client.get(first["download_url"], headers=headers).content
    _upload(client, headers, 303)
    assert run_jobs() == 1  # the new session's detail
    stale = client.get(f"{base}/status", headers=headers).json()
    assert stale["state"] == "ready" and not stale["current"] and stale["sessions"] == 2, stale
    assert client.get(first["download_url"], headers=headers).content == old, "pinned: the old one until replaced"
    assert client.get(base, headers=headers).status_code == 202, "today's data is not in it: a new build"
    assert run_jobs() == 1
    now = client.get(f"{base}/status", headers=headers).json()
    assert now["current"] and now["sessions"] == 3 and now["download_url"] != first["download_url"]
    replaced = client.get(first["download_url"], headers=headers)
    assert replaced.status_code == 410 and replaced.json()["error"] == "ArchiveReplaced", replaced.text
    assert len(_archive_keys(with_store)) == 1, "the replaced archive's object is deleted"
    assert _count(db_session, PatientArchive) == 1


def test_only_the_patient_or_an_admin_asks_reads_or_downloads_it(
    client, run_jobs, with_store, patient_with_sessions, make_user, make_patient_with_therapist, auth_headers
):
    patient, therapist, headers, _ = patient_with_sessions
    base = f"/api/v1/patients/{patient.id}/archive"
    admin = auth_headers(make_user("admin"))
    others = ((auth_headers(therapist), 403), (auth_headers(make_patient_with_therapist()[0]), 404))
    assert client.post(base, headers=admin).status_code == 202 and run_jobs() == 1  # commits the tokens too
    url = client.get(f"{base}/status", headers=admin).json()["download_url"]
    assert client.get(url, headers=admin).status_code == 200
    for who, status in others:
        for method, path in (("POST", base), ("GET", f"{base}/status"), ("GET", base), ("GET", url)):
            response = client.request(method, path, headers=who)
            assert response.status_code == status, (method, path, response.text)
            assert set(response.json()) == {"error", "detail"}
    assert client.get(url).status_code == 401
    bad = client.get(f"{base}?sha256=nothex", headers=headers)
    assert bad.status_code == 422 and set(bad.json()) == {"error", "detail"}


def test_erasure_deletes_the_archive_and_its_queued_build(
    client, db_session, run_jobs, with_store, patient_with_sessions, make_user, auth_headers
):
    patient, _, headers, _ = patient_with_sessions
    base = f"/api/v1/patients/{patient.id}/archive"
    assert client.post(base, headers=headers).status_code == 202 and run_jobs() == 1
    _upload(client, headers, 304)
    assert run_jobs() == 1 and client.post(base, headers=headers).status_code == 202  # a new build queued
    assert len(_archive_keys(with_store)) == 1
    admin = auth_headers(make_user("admin"))
    erased = client.post(f"/api/v1/patients/{patient.id}/erasure", json={"confirm_email": patient.email},
                         headers=admin)  # fmt: skip
    assert erased.status_code == 200 and erased.json()["rows"]["patient_archive"] == 1, erased.text
    assert _archive_keys(with_store) == [] and _count(db_session, PatientArchive) == 0
    assert _count(db_session, Job, Job.kind == "archive") == 0, "no build of an erased patient's archive stays queued"
    assert run_jobs() == 0


def test_a_build_for_a_patient_who_no_longer_exists_keeps_nothing(db_session, with_store, settings):
    result = prepared_archive.run(db_session=db_session, patient_id=10**6, requested_by="the patient",
                                  settings=settings)  # fmt: skip
    assert result["skipped"] == "the patient no longer exists" and _archive_keys(with_store) == []


def test_a_failing_build_is_said_and_asked_again(
    client, db_session, run_jobs, with_store, patient_with_sessions, monkeypatch, auth_headers, make_user
):
    patient, _, headers, _ = patient_with_sessions
    base = f"/api/v1/patients/{patient.id}/archive"

    def broken(**kw):
        raise RuntimeError("the disk is full")

    monkeypatch.setattr(prepared_archive, "build_archive", broken)
    assert client.post(base, headers=headers).status_code == 202
    db_session.execute(sa.update(Job).where(Job.kind == "archive").values(max_attempts=2))
    assert run_jobs() == 1
    retrying = client.get(f"{base}/status", headers=headers).json()
    assert retrying["state"] == "preparing" and "The last try failed; a worker will try again" in retrying["detail"]
    past = dt.datetime(2020, 1, 1, tzinfo=dt.UTC)
    db_session.execute(sa.update(Job).where(Job.kind == "archive").values(run_after=past))
    assert run_jobs() == 1
    failed = client.get(f"{base}/status", headers=headers)
    assert failed.status_code == 200 and failed.json()["state"] == "failed", failed.text
    detail = failed.json()["detail"]
    assert detail.startswith("Your archive could not be made: ") and "disk" not in detail, "a patient: no internals"
    by_admin = client.get(f"{base}/status", headers=auth_headers(make_user("admin"))).json()["detail"]
    assert by_admin.startswith("The archive of this patient's data could not be made: "), by_admin
    assert "the disk is full" in by_admin, "an admin: the program's own words"
    assert _count(db_session, PatientArchive) == 0 and _archive_keys(with_store) == [], "nothing kept"
    monkeypatch.undo()
    again = client.post(base, headers=headers)
    assert again.status_code == 202 and again.json()["state"] == "preparing", "asked again: tried again"
    assert run_jobs() == 1 and client.get(f"{base}/status", headers=headers).json()["state"] == "ready"


def test_a_running_build_reports_progress_and_renews_its_lease(db_session, make_user, monkeypatch):
    patient = make_user("patient")
    job = Job(kind="archive", key=f"archive:{patient.id}:x", payload={"patient_id": patient.id}, status="running",
              attempts=1, locked_by="w", locked_until=dt.datetime(2020, 1, 1, tzinfo=dt.UTC))  # fmt: skip
    db_session.add(job)
    db_session.flush()
    monkeypatch.setattr(prepared_archive, "PROGRESS_EVERY_S", 0.0)
    progress = prepared_archive.progress_reporter(db_session, job.id)
    progress(40, 120)
    db_session.refresh(job)
    assert job.result == {"progress": {"done": 40, "total": 120}}
    assert job.locked_until is not None
    assert job.locked_until > dt.datetime.now(dt.UTC) + LEASE - dt.timedelta(minutes=1)
    state = prepared_archive.job_state(job, ENGLISH, None)
    assert state.state == "preparing" and state.progress == (40, 120)


def test_storage_check_reads_the_kept_archive_and_retention_deletes_it(
    client, db_session, run_jobs, with_store, patient_with_sessions
):
    patient, _, headers, ids = patient_with_sessions
    assert client.post(f"/api/v1/patients/{patient.id}/archive", headers=headers).status_code == 202 and run_jobs() == 1
    (key,) = _archive_keys(with_store)
    report = check(db_session.connection(), with_store)
    assert report.ok and key not in report.orphans, "the archive's object is named by its row and checked"
    old = db_session.get(ExerciseSession, ids[0])
    old.started_at = dt.datetime(2025, 1, 1, tzinfo=dt.UTC)
    db_session.flush()
    apply_retention(db_session=db_session, days=365, now=dt.datetime(2026, 11, 27, tzinfo=dt.UTC))
    db_session.commit()
    assert _archive_keys(with_store) == [] and _count(db_session, PatientArchive) == 0, "it held the removed file"
    assert client.get(f"/api/v1/patients/{patient.id}/archive/status", headers=headers).json()["state"] == "none"


def test_the_worker_builds_and_stores_an_archive_in_bounded_memory(db_session, settings, make_user, exercise,
                                                                    tmp_path):  # fmt: skip
    """An archive 24 times a session file is built into a spooled temporary file and stored from it a chunk at a
    time: the build's Python memory (tracemalloc: bytes, buffers, arrays) peaks far below the zip's size, where
    holding the zip (and reading it back to store it) would take twice the size. The local store: moto's S3 server
    runs in this process and keeps what it is sent in its memory (test_stores holds both to the same bytes)."""
    before = factory._store
    factory.use_store(local_store(tmp_path))
    try:
        patient = make_user("patient")
        rng, first = np.random.default_rng(20261128), dt.datetime(2026, 10, 1, tzinfo=dt.UTC)
        for k in range(24):  # 2 MiB of random bytes each: deflate cannot shrink them, the zip is as large
            data = rng.bytes(2 * 2**20)
            obj = get_store().put("session", data)
            row = store_session(db_session, patient, exercise, first + dt.timedelta(days=k), data=b"")
            row.file_bytes, row.file_key, row.content_hash, row.file_size = None, obj.key, obj.sha256, obj.size
        db_session.flush()
        tracemalloc.start()
        try:
            made = prepared_archive.run(db_session=db_session, patient_id=patient.id, requested_by="the patient",
                                        settings=settings)  # fmt: skip
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        kept = prepared_archive.kept_archive(db_session=db_session, patient_id=patient.id)
        assert made["built"] and kept is not None and kept.sessions == 24
        assert kept.size > 48 * 2**20, kept.size
        said = f"the build peaked at {peak / 2**20:.1f} MiB for a {kept.size / 2**20:.1f} MiB zip"
        assert peak < kept.size / 2.5, said
        with zipfile.ZipFile(io.BytesIO(prepared_archive.read_archive(kept))) as z:
            assert sum(n.startswith("sessions/") for n in z.namelist()) == 24 and z.testzip() is None
    finally:
        factory.use_store(before)
