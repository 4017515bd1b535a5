"""Password login, cookie flags, CSRF, logout and login throttling."""

from __future__ import annotations

from fastapi.testclient import TestClient
from sqlalchemy import select

from backend.config import Settings
from backend.users.models import LoginAttempt
from tests.backend.conftest import PASSWORD, make_test_app


def _login(client, email, password=PASSWORD):
    return client.post("/api/v1/auth/login", json={"email": email, "password": password})


def test_login_sets_httponly_lax_cookie_and_returns_csrf(client, make_user):
    user = make_user("therapist", password=PASSWORD)
    r = _login(client, user.email.upper())
    assert r.status_code == 200, r.text
    cookie = r.headers["set-cookie"]
    assert "coach_session=khs_" in cookie and "HttpOnly" in cookie and "SameSite=lax" in cookie
    assert "Secure" not in cookie  # ENVIRONMENT=local over http
    assert r.json()["user"]["id"] == user.id and len(r.json()["csrf_token"]) > 20
    assert client.get("/api/v1/users/me").json()["email"] == user.email
    assert client.get("/api/v1/auth/csrf").json()["csrf_token"] == r.json()["csrf_token"]


def test_cookie_is_secure_outside_local(db_session, make_user):
    settings = Settings(ENVIRONMENT="production", CHECK_MIGRATIONS=False)
    user = make_user("patient", password=PASSWORD)
    with TestClient(make_test_app(db_session, settings), base_url="https://testserver") as client:
        r = _login(client, user.email)
    assert r.status_code == 200 and "Secure" in r.headers["set-cookie"]


def test_wrong_password_is_401_with_error_body(client, make_user):
    user = make_user("patient", password=PASSWORD)
    r = _login(client, user.email, "wrong password!")
    assert r.status_code == 401
    assert r.json()["error"] == "NotAuthenticated"


def test_cookie_unsafe_request_needs_csrf_header(client, make_user):
    user = make_user("patient", password=PASSWORD)
    csrf = _login(client, user.email).json()["csrf_token"]
    r = client.post("/api/v1/tokens", json={"name": "x"})
    assert r.status_code == 403 and r.json()["error"] == "CsrfFailed"
    r = client.post("/api/v1/tokens", json={"name": "x"}, headers={"X-CSRF-Token": "wrong"})
    assert r.status_code == 403 and r.json()["error"] == "CsrfFailed"
    r = client.post("/api/v1/tokens", json={"name": "x"}, headers={"X-CSRF-Token": csrf})
    assert r.status_code == 201, r.text


def test_logout_ends_the_session(client, make_user):
    user = make_user("patient", password=PASSWORD)
    csrf = _login(client, user.email).json()["csrf_token"]
    cookie = client.cookies.get("coach_session")
    assert client.post("/api/v1/auth/logout", headers={"X-CSRF-Token": csrf}).status_code == 204
    client.cookies.set("coach_session", cookie)  # a stolen copy of the cookie no longer works either
    assert client.get("/api/v1/users/me").status_code == 401


def test_five_failures_throttle_with_retry_after(client, make_user, db_session):
    user = make_user("patient", password=PASSWORD)
    for _ in range(5):
        assert _login(client, user.email, "wrong password!").status_code == 401
    r = _login(client, user.email)  # even the right password is refused while throttled
    assert r.status_code == 429 and r.json()["error"] == "TooManyLoginAttempts"
    assert 0 < int(r.headers["Retry-After"]) <= 15 * 60
    failures = db_session.scalars(select(LoginAttempt).where(LoginAttempt.email == user.email)).all()
    assert len(failures) == 5 and not any(a.succeeded for a in failures)


def test_deactivated_user_cannot_log_in(client, make_user, auth_headers):
    admin = make_user("admin")
    user = make_user("patient", password=PASSWORD)
    r = client.patch(f"/api/v1/users/{user.id}", json={"is_active": False}, headers=auth_headers(admin))
    assert r.status_code == 200 and r.json()["is_active"] is False
    assert _login(client, user.email).status_code == 401


def test_validation_errors_use_the_error_body(client):
    r = client.post("/api/v1/auth/login", json={"email": "a@b.org"})
    assert r.status_code == 422
    assert r.json() == {"error": "ValidationError", "detail": "body.password: Field required"}
