"""Deactivating a patient ends everything, their paired home computers too: every device token of theirs is
refused (401) until the patient is active again."""

from __future__ import annotations

import pytest

from tests.backend.khs_files import make_khs

ENDPOINTS = (
    ("GET", "/api/v1/devices/me"),
    ("GET", "/api/v1/patients/{patient}/plans"),
    ("GET", "/api/v1/events"),
)


def _deactivate(client, admin_headers, patient, active: bool = False):
    response = client.patch(f"/api/v1/users/{patient.id}", json={"is_active": active}, headers=admin_headers)
    assert response.status_code == 200, response.text


@pytest.mark.parametrize(("method", "path"), ENDPOINTS)
def test_a_deactivated_patients_device_is_refused(client, make_user, auth_headers, device_headers, method, path):
    patient, admin = make_user("patient"), make_user("admin")
    _, headers = device_headers(patient)
    url = path.format(patient=patient.id)
    if method == "GET" and path != "/api/v1/events":
        assert client.request(method, url, headers=headers).status_code == 200
    _deactivate(client, auth_headers(admin), patient)
    response = client.request(method, url, headers=headers)
    assert response.status_code == 401, response.text
    assert response.json()["detail"] == "the patient of this device is deactivated"


def test_a_deactivated_patients_device_cannot_upload(client, make_user, auth_headers, device_headers):
    patient, admin = make_user("patient"), make_user("admin")
    _, headers = device_headers(patient)
    _deactivate(client, auth_headers(admin), patient)
    response = client.post("/api/v1/sessions", content=make_khs("squat", 2, seed=3), params={"exercise": "squat"},
                           headers=headers | {"Content-Type": "application/octet-stream"})  # fmt: skip
    assert response.status_code == 401, response.text


def test_a_reactivated_patients_device_works_again(client, make_user, auth_headers, device_headers):
    patient, admin = make_user("patient"), make_user("admin")
    _, headers = device_headers(patient)
    _deactivate(client, auth_headers(admin), patient)
    _deactivate(client, auth_headers(admin), patient, active=True)
    assert client.get("/api/v1/devices/me", headers=headers).status_code == 200
