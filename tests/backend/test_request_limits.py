"""Malformed requests get a 4xx that says what was wrong, on SQLite and PostgreSQL alike, and store nothing:
NUL characters in text (PostgreSQL cannot store them), NUL in the URL, JSON bodies far larger than any form."""

from __future__ import annotations

import json

import pytest
from sqlalchemy import func, select

from backend.plans.models import Plan
from backend.users.models import User
from tests.backend.conftest import PASSWORD


@pytest.fixture
def commit(db_session):
    """Commits the set-up, so that a request that fails (and rolls back) cannot take it with it."""
    return db_session.commit


def test_nul_in_a_login_email_is_422(client):
    r = client.post("/api/v1/auth/login", json={"email": "a\u0000@example.org", "password": "x" * 12})
    assert r.status_code == 422 and "NUL" in r.json()["detail"], r.text


def test_nul_in_a_new_users_name_is_422_and_stores_nothing(client, db_session, make_user, auth_headers, commit):
    headers = auth_headers(make_user("admin"))
    commit()
    body = {"email": "nul@example.org", "role": "patient", "password": "0123456789", "full_name": "Ro\u0000se"}
    r = client.post("/api/v1/users", json=body, headers=headers)
    assert r.status_code == 422 and r.json()["error"] == "InvalidInput" and "NUL" in r.json()["detail"], r.text
    assert db_session.scalar(select(func.count()).select_from(User).where(User.email == "nul@example.org")) == 0


def test_nul_in_a_plan_title_or_a_token_name_is_422(client, db_session, make_patient_with_therapist, auth_headers,
                                                     exercise, commit):  # fmt: skip
    patient, therapist = make_patient_with_therapist()
    headers = auth_headers(therapist)
    commit()
    plan = {"title": "Knee\u0000", "start_date": "2026-11-23", "items": []}
    r = client.post(f"/api/v1/patients/{patient.id}/plans", json=plan, headers=headers)
    assert r.status_code == 422 and "NUL" in r.json()["detail"], r.text
    r = client.post("/api/v1/tokens", json={"name": "x\u0000", "scopes": ["read"]}, headers=headers)
    assert r.status_code == 422 and "NUL" in r.json()["detail"], r.text
    assert db_session.scalar(select(func.count()).select_from(Plan).where(Plan.patient_id == patient.id)) == 0


@pytest.mark.parametrize("path", ["/static/app.css%00.js", "/api/v1/sessions?since=2026%00", "/%00"])
def test_nul_in_the_url_is_400(client, path):
    r = client.get(path, headers={"Accept": "application/json"})
    assert r.status_code == 400 and r.json() == {"error": "InvalidInput", "detail": "the URL contains a NUL character"}


def test_a_json_body_larger_than_any_form_is_413_before_it_is_read(client, make_user):
    user = make_user("patient", password=PASSWORD)
    big = json.dumps({"email": user.email, "password": PASSWORD, "pad": "x" * (2 * 2**20)})
    r = client.post("/api/v1/auth/login", content=big, headers={"Content-Type": "application/json"})
    assert r.status_code == 413 and r.json()["error"] == "RequestTooLarge", r.text
    assert "1048576" in r.json()["detail"]


def test_a_body_of_many_unknown_fields_gets_a_short_answer(client, make_patient_with_therapist, auth_headers):
    patient, therapist = make_patient_with_therapist()
    body = ("{" + ",".join(f'"k{i}":1' for i in range(50_000)) + "}").encode()
    headers = auth_headers(therapist) | {"Content-Type": "application/json"}
    r = client.post(f"/api/v1/patients/{patient.id}/suggestions", content=body, headers=headers)
    assert r.status_code == 422
    assert len(r.content) < 2000, f"{len(r.content)} bytes of answer to {len(body)} bytes of request"
    assert r.json()["detail"].startswith("body.text: Field required") and r.json()["detail"].endswith("and 49991 more")
