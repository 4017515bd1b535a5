"""Credentials end when they should: a password change ends the user's logins (and API tokens unless the admin
keeps them), tokens expire (default and maximum documented), and a token made with a token dies with it."""

from __future__ import annotations

import datetime as dt
from typing import Any

import pytest
from sqlalchemy import update

from backend.database import utcnow
from backend.users.models import ApiToken
from tests.backend.conftest import PASSWORD

NEW_PASSWORD = "a brand new passphrase"


def _cookie_login(client, user) -> dict[str, Any]:
    r = client.post("/api/v1/auth/login", json={"email": user.email, "password": PASSWORD})
    assert r.status_code == 200, r.text
    return {"X-CSRF-Token": r.json()["csrf_token"]}


def _token(client, headers, **body) -> dict[str, Any]:
    r = client.post("/api/v1/tokens", json={"name": "t", "scopes": ["read", "write"]} | body, headers=headers)
    assert r.status_code == 201, r.text
    return r.json()


@pytest.mark.parametrize(("keep_api_tokens", "token_status"), [(None, 401), (True, 200)])
def test_a_password_change_ends_logins_and_tokens_unless_the_admin_keeps_the_tokens(
    client, db_session, make_user, auth_headers, keep_api_tokens, token_status
):
    user, admin = make_user("therapist", password=PASSWORD), make_user("admin")
    admin_hdr = auth_headers(admin)
    csrf = _cookie_login(client, user)
    token = _token(client, csrf)["token"]
    db_session.commit()
    body = {"password": NEW_PASSWORD} | ({} if keep_api_tokens is None else {"keep_api_tokens": keep_api_tokens})
    r = client.patch(f"/api/v1/users/{user.id}", json=body, headers=admin_hdr)
    assert r.status_code == 200, r.text
    assert client.get("/api/v1/users/me").status_code == 401  # the old cookie, either way
    client.cookies.clear()
    r = client.get("/api/v1/users/me", headers={"Authorization": f"Bearer {token}"})
    assert r.status_code == token_status, r.text


def test_tokens_expire_after_90_days_by_default_and_at_most_after_365(client, make_user, auth_headers):
    headers = auth_headers(make_user("therapist"))
    made = _token(client, headers)
    expires = dt.datetime.fromisoformat(made["expires_at"])
    assert abs((expires - utcnow()) - dt.timedelta(days=90)) < dt.timedelta(minutes=1), made
    assert _token(client, headers, expires_in_days=7)["expires_at"] < made["expires_at"]
    r = client.post("/api/v1/tokens", json={"name": "t", "expires_in_days": 366}, headers=headers)
    assert r.status_code == 422 and "expires_in_days" in r.json()["detail"], r.text


def test_an_expired_token_is_refused(client, db_session, make_user, auth_headers):
    headers = auth_headers(make_user("therapist"))
    made = _token(client, headers)
    db_session.execute(update(ApiToken).where(ApiToken.id == made["id"]).values(expires_at=utcnow()))
    db_session.commit()
    r = client.get("/api/v1/users/me", headers={"Authorization": f"Bearer {made['token']}"})
    assert r.status_code == 401 and "expired" in r.json()["detail"], r.text


def test_a_token_made_with_a_token_dies_with_it(client, db_session, make_user, auth_headers):
    user = make_user("therapist", password=PASSWORD)
    csrf = _cookie_login(client, user)
    parent = _token(client, csrf)
    client.cookies.clear()
    child = _token(client, {"Authorization": f"Bearer {parent['token']}"})
    assert child["parent_id"] == parent["id"]
    db_session.commit()
    csrf = _cookie_login(client, user)
    assert client.delete(f"/api/v1/tokens/{parent['id']}", headers=csrf).status_code == 204
    client.cookies.clear()
    r = client.get("/api/v1/users/me", headers={"Authorization": f"Bearer {child['token']}"})
    assert r.status_code == 401, r.text
