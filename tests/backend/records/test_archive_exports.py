"""The patient's archive (format 3) holds each session's exports (csv, fhir) and a manifest; a session whose file is
missing or corrupt is named, and the rest of the archive is still given (HTTP API and command line)."""

from __future__ import annotations

import csv
import hashlib
import io
import json
import zipfile
from typing import Any

import pytest
import sqlalchemy as sa

from backend import cli
from backend.records import commands
from backend.records.archive import EXPORT_FORMATS, FORMAT_VERSION
from backend.sessions.models import ExerciseSession
from tests.backend.khs_files import make_khs

R4B = pytest.importorskip("fhir.resources.R4B.bundle", reason="fhir.resources is in the test extra")


def _upload(client, headers, seed: int, exercise: str = "squat") -> int:
    response = client.post("/api/v1/sessions", content=make_khs(exercise, 2, seed=seed),
                           headers={"Content-Type": "application/octet-stream", **headers},
                           params={"exercise": exercise})  # fmt: skip
    assert response.status_code == 201, response.text
    return response.json()["id"]


def _observations(bundle: dict[str, Any]) -> list[tuple[str, object]]:
    """Returns (code, value) of every Observation of a FHIR Bundle (its entries' fullUrls are new uuids each time)."""
    out = []
    for entry in bundle["entry"]:
        r = entry["resource"]
        assert r["resourceType"] in ("Observation", "Device"), r
        if r["resourceType"] == "Device":
            continue
        value = r.get("valueQuantity", {}).get("value", r.get("valueInteger"))
        out.append((r["code"]["coding"][0]["code"], value))
    return sorted(out, key=repr)


def _check_session_exports(z: zipfile.ZipFile, entry: dict[str, Any]) -> None:
    """Asserts a session's entry names an export of each format and that each parses and fits the session."""
    assert sorted(entry["exports"]) == sorted(EXPORT_FORMATS) and entry["exports_missing"] == {}, entry
    sid = entry["id"]
    with zipfile.ZipFile(io.BytesIO(z.read(entry["exports"]["csv"]))) as tables:
        assert {"metrics.csv", "repetitions.csv", "recording.csv", "angles_raw.csv"} <= set(tables.namelist())
        angles = list(csv.reader(io.StringIO(tables.read("angles_raw.csv").decode())))
        assert angles[0][0] == "time_s" and len(angles) == entry["n_frames"] + 1, (sid, len(angles))
        assert all(len(r) == len(angles[0]) for r in angles) and float(angles[-1][0]) > 0
        metrics = list(csv.DictReader(io.StringIO(tables.read("metrics.csv").decode())))
        assert metrics, f"session {sid}: metrics.csv is empty"
    bundle = json.loads(z.read(entry["exports"]["fhir"]))
    assert (bundle["resourceType"], bundle["type"]) == ("Bundle", "collection")
    R4B.Bundle.model_validate(bundle)  # a Bundle the FHIR R4B models accept
    reps = [v for code, v in _observations(bundle) if code == "repetitions"]
    assert reps == [entry["metrics"]["repetitions"]], (sid, reps)


def _check_manifest(z: zipfile.ZipFile, listed: list[dict[str, Any]]) -> dict[str, Any]:
    manifest = json.loads(z.read("manifest.json"))
    assert manifest["format_version"] == FORMAT_VERSION == "3"
    members = {m["name"]: m for m in manifest["files"]}
    assert set(members) == set(z.namelist()) - {"manifest.json"}
    for name, m in members.items():
        data = z.read(name)
        assert (m["size"], m["sha256"]) == (len(data), hashlib.sha256(data).hexdigest()), name
    assert [(s["id"], s["exports"]) for s in manifest["sessions"]] == [(s["id"], s["exports"]) for s in listed]
    return manifest


def test_every_session_has_its_exports_and_a_broken_file_is_named(
    fetch_archive, client, db_session, make_patient_with_therapist, auth_headers, with_store
):
    patient, therapist = make_patient_with_therapist()
    headers = auth_headers(patient)
    good = [_upload(client, headers, 201), _upload(client, headers, 202, "elbow_flexion")]
    corrupt, missing = _upload(client, headers, 203), _upload(client, headers, 204)
    db_session.execute(sa.update(ExerciseSession).where(ExerciseSession.id == corrupt).values(content_hash="1" * 64))
    with_store.delete(db_session.get(ExerciseSession, missing).file_key)
    db_session.flush()

    response = fetch_archive(patient.id, headers)
    assert response.status_code == 200, response.text
    assert response.headers["x-archive-incomplete-sessions"] == "2"
    z = zipfile.ZipFile(io.BytesIO(response.content))
    listed = json.loads(z.read("sessions.json"))
    by_id = {s["id"]: s for s in listed}
    for sid in good:
        _check_session_exports(z, by_id[sid])
        api = client.get(f"/api/v1/sessions/{sid}/export", params={"format": "csv"}, headers=auth_headers(therapist))
        assert api.status_code == 200 and z.read(by_id[sid]["exports"]["csv"]) == api.content, sid
        fhir = client.get(f"/api/v1/sessions/{sid}/export", params={"format": "fhir"}, headers=headers)
        assert _observations(json.loads(z.read(by_id[sid]["exports"]["fhir"]))) == _observations(fhir.json()), sid
    for sid, says in ((corrupt, "is damaged"), (missing, "is missing")):
        entry = by_id[sid]
        assert entry["file"] is None and says in entry["file_missing_reason"], entry
        # the patient reads why, not where the server keeps its files
        where = str(getattr(with_store, "root", "") or getattr(with_store, "bucket", ""))
        assert (
            where and where not in entry["file_missing_reason"] and "stored object" not in entry["file_missing_reason"]
        )
        assert entry["exports"] == {} and sorted(entry["exports_missing"]) == sorted(EXPORT_FORMATS), entry
        assert entry["metrics"]["repetitions"] >= 0, "the metrics of a session without its file are still given"
    readme = z.read("README.txt").decode()
    assert "Archive format version 3" in readme and "Sessions not complete in this archive (2)" in readme
    assert f"session {corrupt}: file: " in readme and f"session {missing}: file: " in readme
    assert all(f"session {sid}:" not in readme for sid in good)
    assert all(name in readme for name in ("exports/session-N/", "session-N-csv.zip", "session-N-fhir.json",
                                           "manifest.json"))  # fmt: skip
    manifest = _check_manifest(z, listed)
    assert [s["id"] for s in manifest["incomplete_sessions"]] == sorted([corrupt, missing])


def test_an_archive_with_every_file_readable_says_nothing_is_missing(
    fetch_archive, client, make_user, auth_headers, with_store
):
    patient = make_user("patient")
    headers = auth_headers(patient)
    sid = _upload(client, headers, 211)
    response = fetch_archive(patient.id, headers)
    assert response.status_code == 200 and response.headers["x-archive-incomplete-sessions"] == "0"
    z = zipfile.ZipFile(io.BytesIO(response.content))
    (entry,) = json.loads(z.read("sessions.json"))
    assert entry["id"] == sid
    _check_session_exports(z, entry)
    assert "not complete" not in z.read("README.txt").decode()
    assert _check_manifest(z, [entry])["incomplete_sessions"] == []


def test_the_command_line_archive_holds_the_exports_and_names_a_missing_file(
    client, db_session, make_user, auth_headers, with_store, tmp_path
):
    patient, admin = make_user("patient"), make_user("admin")
    headers = auth_headers(patient)
    ok, gone = _upload(client, headers, 221), _upload(client, headers, 222)
    with_store.delete(db_session.get(ExerciseSession, gone).file_key)
    out = tmp_path / "p.zip"
    args = cli.build_parser().parse_args(["patient-data", "archive", str(patient.id), "--admin", admin.email,
                                          "--out", str(out)])  # fmt: skip
    said = commands.run(args, db_session)
    assert f"1 session(s) incomplete, named in its README.txt: {gone}" in said, said
    z = zipfile.ZipFile(out)
    listed = json.loads(z.read("sessions.json"))
    by_id = {s["id"]: s for s in listed}
    _check_session_exports(z, by_id[ok])
    assert by_id[gone]["exports"] == {} and "is missing" in by_id[gone]["exports_missing"]["csv"]
    assert f"session {gone}: file: " in z.read("README.txt").decode()
    assert f"admin {admin.email}" in z.read("README.txt").decode()
    _check_manifest(z, listed)


def test_a_stored_export_is_read_checked_and_a_damaged_one_made_again(
    fetch_archive, client, db_session, make_user, auth_headers, with_store
):
    from backend.sessions import prepared_export
    from backend.sessions.models import SessionExport

    patient = make_user("patient")
    headers = auth_headers(patient)
    kept, damaged = _upload(client, headers, 231), _upload(client, headers, 232)
    for sid in (kept, damaged):
        done = prepared_export.run(db_session=db_session, session_id=sid, fmt="csv", max_frames=10**6,
                                   max_decoded_bytes=1 << 30)  # fmt: skip
        assert done["built"], done
    stored_csv = client.get(f"/api/v1/sessions/{kept}/export", params={"format": "csv"}, headers=headers).content
    with_store.delete(db_session.get(ExerciseSession, kept).file_key)  # the .khs goes; its stored csv stays
    db_session.execute(sa.update(SessionExport).where(SessionExport.session_id == damaged).values(data_hash="2" * 64))
    db_session.flush()
    response = fetch_archive(patient.id, headers)
    assert response.status_code == 200 and response.headers["x-archive-incomplete-sessions"] == "1"
    z = zipfile.ZipFile(io.BytesIO(response.content))
    by_id = {s["id"]: s for s in json.loads(z.read("sessions.json"))}
    assert by_id[kept]["file"] is None and z.read(by_id[kept]["exports"]["csv"]) == stored_csv
    assert list(by_id[kept]["exports_missing"]) == ["fhir"], "fhir is made from the .khs file, which is gone"
    _check_session_exports(z, by_id[damaged])  # the damaged stored csv is made again from the session file


def test_a_long_recording_s_exports_are_in_the_first_archive_the_worker_makes(
    fetch_archive, client, db_session, make_user, auth_headers, with_store, settings
):
    from backend.jobs.models import Job

    patient = make_user("patient")
    headers = auth_headers(patient)
    sid = _upload(client, headers, 241)
    settings.EXPORT_DIRECT_MAX_FRAMES = 10  # every recording is long: the session page's downloads go to a worker
    first = fetch_archive(patient.id, headers)  # the archive's worker exports it: no request limit applies there
    assert first.status_code == 200 and first.headers["x-archive-incomplete-sessions"] == "0"
    z = zipfile.ZipFile(io.BytesIO(first.content))
    (entry,) = json.loads(z.read("sessions.json"))
    _check_session_exports(z, entry)
    assert db_session.scalars(sa.select(Job.key).where(Job.kind == "export")).all() == [], "no export job queued"
    stored = client.get(f"/api/v1/sessions/{sid}/export", params={"format": "csv"}, headers=headers)
    assert stored.status_code == 202, "the session page's download of a long recording is still the export worker's"
