"""Headers that bound what the pages may do in a browser, the replay viewer's narrowed query, and URLs that never
come from the request's Host header (backend.security_headers, frontend.pages.replay_viewer)."""

from __future__ import annotations

import datetime as dt
from urllib.parse import quote

import pytest
from fastapi.testclient import TestClient

from backend.config import Settings
from backend.security_headers import PAGE_POLICY, VIEWER_POLICY
from tests.backend.conftest import PASSWORD, make_test_app
from tests.backend.khs_files import make_khs

T0 = dt.datetime(2026, 11, 2, 9, 0, tzinfo=dt.UTC)
HTML = {"Accept": "text/html"}


def _directives(policy: str) -> dict[str, list[str]]:
    return {part.split()[0]: part.split()[1:] for part in policy.split(";") if part.strip()}


def _viewer(client, headers, query: str):
    return client.get(f"/replay/viewer/?{query}", headers=headers | HTML)


@pytest.fixture
def therapist_headers(make_patient_with_therapist, auth_headers):
    _patient, therapist = make_patient_with_therapist()
    return auth_headers(therapist)


@pytest.mark.parametrize(
    "query",
    [
        "playbackPath=" + quote("http://127.0.0.1:8799/x.viser", safe=""),  # a recording from another site
        "playbackPath=" + quote("//evil.example/x.viser", safe=""),
        "playbackPath=" + quote("https://evil.example/api/v1/sessions/1/replay", safe=""),
        "playbackPath=" + quote("/api/v1/sessions/1/file", safe=""),  # this origin, but not a replay
        "playbackPath=" + quote("/api/v1/sessions/1/replay/../../../x", safe=""),
        "playbackPath=" + quote("/api/v1/sessions/1/replay", safe="") + "&websocket=ws://127.0.0.1:8799",
        "websocket=ws://127.0.0.1:8799",  # viser's client connects to any scene server named here
        "playbackPath=" + quote("/api/v1/sessions/1/replay", safe="") + "&playbackPath=http://evil.example/x",
        "",
    ],
)
def test_replay_viewer_refuses_a_recording_from_anywhere_but_a_session_replay(client, therapist_headers, query):
    r = _viewer(client, therapist_headers, query)
    assert r.status_code == 404, f"{query!r}: {r.status_code}"
    assert "Viser" not in r.text


def test_replay_viewer_serves_viser_for_a_session_replay(client, therapist_headers):
    r = _viewer(client, therapist_headers, "playbackPath=" + quote("/api/v1/sessions/12/replay", safe=""))
    assert r.status_code == 200 and "<title>Session replay</title>" in r.text, "viser's client, in the reader's words"
    assert r.headers["content-security-policy"] == VIEWER_POLICY


def test_replay_viewer_behind_a_prefix_wants_the_prefixed_path(db_session, make_patient_with_therapist, auth_headers):
    settings = Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, DATABASE_URL="sqlite://",
                        PUBLIC_URL="https://coach.example.org/clinic")  # fmt: skip
    _patient, therapist = make_patient_with_therapist()
    headers = auth_headers(therapist)
    with TestClient(make_test_app(db_session, settings)) as client:
        prefixed = _viewer(client, headers, "playbackPath=" + quote("/clinic/api/v1/sessions/3/replay", safe=""))
        bare = _viewer(client, headers, "playbackPath=" + quote("/api/v1/sessions/3/replay", safe=""))
    assert (prefixed.status_code, bare.status_code) == (200, 404)
    assert '<script src="/clinic/static/replay_viewer.js"></script>' in prefixed.text, "its scripts under the prefix"


def test_viewer_policy_keeps_connections_on_this_origin():
    viewer = _directives(VIEWER_POLICY)
    assert viewer["connect-src"] == ["'self'", "data:", "blob:"]  # no recording or websocket from elsewhere
    assert viewer["frame-ancestors"] == ["'self'"] and viewer["base-uri"] == ["'none'"]


def test_page_policy_runs_only_this_origins_scripts():
    page = _directives(PAGE_POLICY)
    assert page["script-src"] == ["'self'"]  # no inline script, no eval: injected markup cannot run
    assert page["connect-src"] == ["'self'"] and page["frame-ancestors"] == ["'self'"]
    assert page["object-src"] == ["'none'"] and page["base-uri"] == ["'none'"]


@pytest.mark.parametrize(
    "path, headers",
    [
        ("/", HTML),  # login page
        ("/therapist", HTML),  # redirect to the login page
        ("/no/such/page", HTML),  # 404 page
        ("/static/app.css", {}),
        ("/api/v1/users/me", {}),  # 401 JSON
        ("/healthz", {}),
    ],
)
def test_every_answer_carries_the_browser_security_headers(client, path, headers):
    r = client.get(path, headers=headers, follow_redirects=False)
    assert r.headers["content-security-policy"] == PAGE_POLICY, path
    assert r.headers["x-frame-options"] == "SAMEORIGIN"
    assert r.headers["x-content-type-options"] == "nosniff"
    assert r.headers["referrer-policy"] == "same-origin"
    assert "strict-transport-security" not in r.headers  # served over plain http here


def test_signed_in_pages_carry_the_headers(client, auth_headers, make_patient_with_therapist, store, exercise):
    patient, therapist = make_patient_with_therapist()
    row = store(patient, exercise, T0, data=make_khs("squat", 1, seed=5))
    for path in ("/therapist", f"/therapist/sessions/{row.id}", f"/therapist/sessions/{row.id}/replay"):
        r = client.get(path, headers=auth_headers(therapist) | HTML)
        assert r.status_code == 200, path
        assert r.headers["content-security-policy"] == PAGE_POLICY and r.headers["x-frame-options"] == "SAMEORIGIN"


def test_api_answers_are_not_cached(client, make_patient_with_therapist, auth_headers, store, exercise):
    patient, therapist = make_patient_with_therapist()
    row = store(patient, exercise, T0, data=make_khs("squat", 1, seed=6))
    headers = auth_headers(therapist)
    for path in (f"/api/v1/sessions/{row.id}", f"/api/v1/patients/{patient.id}",
                 f"/api/v1/sessions/{row.id}/export?format=fhir"):  # fmt: skip
        r = client.get(path, headers=headers)
        assert r.status_code == 200 and r.headers["cache-control"] == "no-store", path


def test_hsts_only_when_the_public_url_is_https(db_session):
    https = Settings(ENVIRONMENT="production", CHECK_MIGRATIONS=False, PUBLIC_URL="https://coach.example.org")
    with TestClient(make_test_app(db_session, https)) as client:
        assert client.get("/healthz").headers["strict-transport-security"] == "max-age=31536000"
    for public in ("http://127.0.0.1:8000", "https://localhost", "https://127.0.0.1:8443/clinic", ""):
        settings = Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, PUBLIC_URL=public)
        with TestClient(make_test_app(db_session, settings)) as client:
            assert "strict-transport-security" not in client.get("/healthz").headers, public


def test_cookie_is_secure_when_the_public_url_is_https_even_in_local(db_session, make_user):
    settings = Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, PUBLIC_URL="https://coach.example.org/clinic")
    user = make_user("patient", password=PASSWORD)
    with TestClient(make_test_app(db_session, settings), base_url="https://testserver") as client:
        r = client.post("/api/v1/auth/login", json={"email": user.email, "password": PASSWORD})
    assert r.status_code == 200 and "Secure" in r.headers["set-cookie"]


@pytest.mark.parametrize("path", ["/therapist/", "/patient/", "/api/v1/sessions/", "/replay/viewer"])
def test_a_trailing_slash_never_redirects_to_the_requests_host(client, path):
    r = client.get(path, headers={"Host": "evil.example", "Accept": "text/html"}, follow_redirects=False)
    assert "evil.example" not in r.headers.get("location", ""), r.headers.get("location")
    assert r.status_code == 404


@pytest.mark.parametrize(
    "path",
    [
        "/static/..%2Fpages.py",
        "/static/%2e%2e%2fpages.py",
        "/static/..%2F..%2Fbackend%2Fmain.py",
        "/static/__init__.py",
        "/static/..%5Cpages.py",
        "/static/.%2E/templates/base.html",
        "/static/app.css%00.js",
    ],
)
def test_static_files_stay_in_their_folder(client, path):
    r = client.get(path)
    assert r.status_code in (400, 404), f"{path}: {r.status_code}"
    assert "import" not in r.text and "<html" not in r.text


def test_a_symlink_in_the_static_folder_is_not_followed_out(client, tmp_path, monkeypatch):
    import frontend.pages as pages

    static, outside = tmp_path / "static", tmp_path / "secret.js"
    static.mkdir()
    outside.write_text("const secret = 1;")
    (static / "app.js").write_text("ok();")
    (static / "leak.js").symlink_to(outside)
    monkeypatch.setattr(pages, "STATIC", static)
    assert client.get("/static/app.js").text == "ok();"
    assert client.get("/static/leak.js").status_code == 404


@pytest.mark.parametrize("layer", ["raw", "filtered"])
def test_replay_viewer_serves_one_skeleton_of_a_session_replay(client, therapist_headers, layer):
    r = _viewer(
        client, therapist_headers, "playbackPath=" + quote(f"/api/v1/sessions/12/replay?layer={layer}", safe="")
    )
    assert r.status_code == 200 and "<title>Session replay</title>" in r.text


@pytest.mark.parametrize("tail", ["?layer=both", "?layer=raw&x=1", "?layer=raw#", "?other=raw", "?layer="])
def test_replay_viewer_refuses_any_other_query_of_the_recording(client, therapist_headers, tail):
    r = _viewer(client, therapist_headers, "playbackPath=" + quote(f"/api/v1/sessions/12/replay{tail}", safe=""))
    assert r.status_code == 404, tail
