"""A device that names another device gets the same answer whether that device exists (another patient's, or its
own patient's other computer) or not: device ids cannot be probed."""

from __future__ import annotations

import pytest

from backend.schemas import MAX_ID


@pytest.mark.parametrize("target", ["foreign", "sibling", "missing"])
def test_another_device_and_a_missing_one_get_the_same_answer(client, make_user, device_headers, target):
    patient = make_user("patient")
    _, headers = device_headers(patient)
    if target == "missing":
        device_id = MAX_ID
    else:
        other, _ = device_headers(patient if target == "sibling" else make_user("patient"))
        device_id = other.id
    response = client.delete(f"/api/v1/devices/{device_id}", headers=headers)
    assert response.status_code == 404, response.text
    assert response.json() == {"error": "DeviceNotFound", "detail": f"device {device_id} does not exist"}


def test_a_device_still_revokes_itself(client, make_user, device_headers):
    device, headers = device_headers(make_user("patient"))
    assert client.delete(f"/api/v1/devices/{device.id}", headers=headers).status_code == 204
    assert client.get("/api/v1/devices/me", headers=headers).status_code == 401
