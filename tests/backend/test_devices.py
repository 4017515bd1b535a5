"""Device pairing: codes are single use and expire; device tokens only reach their own patient."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import select

from backend.audit.models import AuditEvent
from backend.devices.models import PairingCode


def _code(client, headers, patient_id):
    r = client.post(f"/api/v1/patients/{patient_id}/pairing-codes", headers=headers)
    assert r.status_code == 201, r.text
    return r.json()["code"]


def test_pairing_code_works_once(client, make_patient_with_therapist, auth_headers):
    patient, therapist = make_patient_with_therapist()
    code = _code(client, auth_headers(therapist), patient.id)
    r = client.post("/api/v1/devices/pair", json={"code": code.lower().replace("-", " "), "name": "kinect"})
    assert r.status_code == 201, r.text
    token = r.json()["token"]
    assert token.startswith("khd_") and r.json()["patient_id"] == patient.id
    again = client.post("/api/v1/devices/pair", json={"code": code})
    assert again.status_code == 403 and again.json()["error"] == "PairingCodeInvalid"
    me = client.get("/api/v1/devices/me", headers={"Authorization": f"Bearer {token}"})
    assert me.status_code == 200 and me.json()["last_seen_at"] is not None


def test_expired_code_is_refused(client, make_user, auth_headers, db_session):
    patient = make_user("patient")
    code = _code(client, auth_headers(patient), patient.id)
    row = db_session.scalar(select(PairingCode).where(PairingCode.patient_id == patient.id))
    row.expires_at = dt.datetime.now(dt.UTC) - dt.timedelta(seconds=1)
    db_session.flush()
    r = client.post("/api/v1/devices/pair", json={"code": code})
    assert r.status_code == 403 and r.json()["error"] == "PairingCodeInvalid"


def test_code_expires_in_about_15_minutes(client, make_user, auth_headers):
    patient = make_user("patient")
    r = client.post(f"/api/v1/patients/{patient.id}/pairing-codes", headers=auth_headers(patient))
    left = dt.datetime.fromisoformat(r.json()["expires_at"]) - dt.datetime.now(dt.UTC)
    assert dt.timedelta(minutes=14) < left <= dt.timedelta(minutes=15)


def test_device_reaches_only_its_patient(client, make_user, device_headers):
    own, other = make_user("patient"), make_user("patient")
    _, headers = device_headers(own)
    assert client.get(f"/api/v1/patients/{own.id}", headers=headers).status_code == 200
    r = client.get(f"/api/v1/patients/{other.id}", headers=headers)
    assert r.status_code == 404 and r.json()["error"] == "PatientNotFound"
    assert client.get("/api/v1/users/me", headers=headers).status_code == 403


def test_revoked_device_is_refused_and_audited(
    client, make_patient_with_therapist, auth_headers, device_headers, db_session
):
    patient, therapist = make_patient_with_therapist()
    device, headers = device_headers(patient)
    assert client.delete(f"/api/v1/devices/{device.id}", headers=auth_headers(therapist)).status_code == 204
    assert client.get("/api/v1/devices/me", headers=headers).status_code == 401
    actions = db_session.scalars(select(AuditEvent.action).where(AuditEvent.patient_id == patient.id)).all()
    assert "device.revoke" in actions


def test_unassigned_therapist_cannot_create_code(client, make_user, auth_headers):
    patient, therapist = make_user("patient"), make_user("therapist")
    r = client.post(f"/api/v1/patients/{patient.id}/pairing-codes", headers=auth_headers(therapist))
    assert r.status_code == 404
