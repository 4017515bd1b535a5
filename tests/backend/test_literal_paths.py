"""A path spelled out in the API (/devices/me, /devices/pair, /users/me) advertises and answers its own methods,
not those of a template that would also match it (/devices/{device_id}, /users/{user_id}): 405 with Allow."""

from __future__ import annotations

import pytest


def _allow(response) -> set[str]:
    return {m.strip() for m in response.headers.get("allow", "").split(",") if m.strip()}


@pytest.mark.parametrize(
    ("path", "methods"),
    [("/api/v1/devices/me", {"GET", "OPTIONS"}), ("/api/v1/devices/pair", {"POST", "OPTIONS"})],
)
def test_options_of_a_literal_path_names_its_own_methods(client, path, methods):
    response = client.options(path)
    assert response.status_code == 204, response.text
    assert _allow(response) == methods


@pytest.mark.parametrize(("method", "path"), [("PATCH", "/api/v1/users/me"), ("DELETE", "/api/v1/devices/me")])
def test_a_method_of_the_template_on_a_literal_path_is_405(client, make_user, auth_headers, method, path):
    response = client.request(method, path, headers=auth_headers(make_user("admin")), json={})
    assert response.status_code == 405, response.text
    assert response.json()["error"] == "MethodNotAllowed"
    assert method not in _allow(response) and "OPTIONS" in _allow(response)


def test_a_template_still_takes_its_ids(client):
    assert _allow(client.options("/api/v1/devices/12")) == {"DELETE", "OPTIONS"}


@pytest.mark.parametrize("role", ["therapist", "patient", None])
def test_patch_users_me_is_405_for_every_caller(client, make_user, auth_headers, role):
    headers = auth_headers(make_user(role)) if role else {}
    response = client.patch("/api/v1/users/me", headers=headers, json={"full_name": "x"})
    assert response.status_code == 405, response.text
    assert response.json()["error"] == "MethodNotAllowed"
    assert _allow(response) == {"GET", "OPTIONS"}
