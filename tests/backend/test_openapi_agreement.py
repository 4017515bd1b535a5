"""The API answers as its OpenAPI document says: date-times are RFC 3339 date-times (no numbers, no bare dates),
every operation lists the answers given before its route (400 for a NUL in the URL, 413/422 for unreadable bodies,
503 for a busy database on writes), OPTIONS is answered with the allowed methods, and 405 names all of them."""

from __future__ import annotations

import pytest


@pytest.fixture
def admin(make_user, auth_headers):
    return auth_headers(make_user("admin"))


@pytest.mark.parametrize("since", ["12345", "1.5", "2026-11-01", "2026-11-01T00:00:00"])
def test_since_takes_only_a_date_time_with_its_offset(client, admin, since):
    r = client.get("/api/v1/sessions", params={"since": since}, headers=admin)
    assert r.status_code == 422 and r.json()["detail"].startswith("query.since:"), r.text


@pytest.mark.parametrize("since", ["2026-11-01T00:00:00Z", "2026-11-01T00:00:00.000Z", "2026-11-01T09:30:00+02:00"])
def test_since_takes_rfc3339_date_times(client, admin, since):
    assert client.get("/api/v1/sessions", params={"since": since}, headers=admin).status_code == 200


def test_options_lists_the_methods_of_the_path(client, admin):
    r = client.options("/api/v1/sessions", headers=admin)
    assert r.status_code == 204, r.text
    assert {m.strip() for m in r.headers["allow"].split(",")} == {"GET", "POST", "OPTIONS"}


def test_a_method_the_path_lacks_is_405_naming_every_allowed_method(client, admin):
    r = client.delete("/api/v1/sessions", headers=admin)
    assert r.status_code == 405 and r.json()["error"] == "MethodNotAllowed", r.text
    assert {m.strip() for m in r.headers["allow"].split(",")} == {"GET", "POST", "OPTIONS"}


def test_a_json_body_that_is_not_utf8_is_422(client, admin):
    r = client.post("/api/v1/tokens", content=b'{"name": "\xff\xfe"}', headers={**admin,
                    "Content-Type": "application/json"})  # fmt: skip
    assert r.status_code == 422 and r.json()["error"] == "InvalidInput" and "UTF-8" in r.json()["detail"], r.text


def test_every_operation_documents_the_answers_given_before_its_route(client):
    paths = client.get("/openapi.json").json()["paths"]
    for path, operations in paths.items():
        for method, op in operations.items():
            codes = set(op["responses"])
            assert "400" in codes, f"{method} {path}"
            if "requestBody" in op:
                assert {"413", "422"} <= codes, f"{method} {path}"
            if method != "get":
                assert "503" in codes, f"{method} {path}"
