"""Personal API tokens: shown once, scopes enforced, revocable."""

from __future__ import annotations


def test_token_created_once_listed_without_secret(client, make_user, auth_headers):
    user = make_user("therapist")
    headers = auth_headers(user)
    r = client.post("/api/v1/tokens", json={"name": "nb", "scopes": ["read"]}, headers=headers)
    assert r.status_code == 201 and r.json()["token"].startswith("khc_")
    listed = client.get("/api/v1/tokens", headers=headers).json()
    assert listed["total"] == 2 and all("token" not in t for t in listed["items"])


def test_read_scope_cannot_write(client, make_user, auth_headers):
    user = make_user("therapist")
    token = client.post("/api/v1/tokens", json={"name": "ro", "scopes": ["read"]}, headers=auth_headers(user))
    ro = {"Authorization": f"Bearer {token.json()['token']}"}
    assert client.get("/api/v1/users/me", headers=ro).status_code == 200
    r = client.post("/api/v1/tokens", json={"name": "x", "scopes": ["read"]}, headers=ro)
    assert r.status_code == 403 and r.json()["error"] == "InsufficientScope"


def test_write_only_token_cannot_read(client, make_user, auth_headers):
    user = make_user("therapist")
    r = client.get("/api/v1/users/me", headers=auth_headers(user, scopes=("write",)))
    assert r.status_code == 403 and r.json()["detail"] == "this API token lacks the 'read' scope"


def test_revoked_token_is_refused(client, make_user, auth_headers):
    user = make_user("patient")
    headers = auth_headers(user)
    created = client.post("/api/v1/tokens", json={"name": "t", "scopes": ["read", "write"]}, headers=headers).json()
    other = {"Authorization": f"Bearer {created['token']}"}
    assert client.delete(f"/api/v1/tokens/{created['id']}", headers=headers).status_code == 204
    r = client.get("/api/v1/users/me", headers=other)
    assert r.status_code == 401 and r.json()["error"] == "NotAuthenticated"


def test_cannot_revoke_token_of_someone_else(client, make_user, auth_headers):
    a, b = make_user("patient"), make_user("patient")
    created = client.post("/api/v1/tokens", json={"name": "t"}, headers=auth_headers(a)).json()
    r = client.delete(f"/api/v1/tokens/{created['id']}", headers=auth_headers(b))
    assert r.status_code == 404 and r.json()["error"] == "TokenNotFound"


def test_garbage_bearer_is_401(client):
    for value in ("Bearer nope", "Basic abc", "Bearer khc_unknown"):
        r = client.get("/api/v1/users/me", headers={"Authorization": value})
        assert r.status_code == 401, value
