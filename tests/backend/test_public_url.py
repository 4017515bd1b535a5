"""URLs the pages build come from COACH_PUBLIC_URL (its path prefixes them), never from the request's Host."""

from __future__ import annotations

import datetime as dt
import re

import pytest
from fastapi.testclient import TestClient

from backend.config import Settings
from tests.backend.conftest import make_test_app
from tests.backend.khs_files import make_khs

T0 = dt.datetime(2026, 11, 2, 9, 0, tzinfo=dt.UTC)
EVIL = {"Host": "evil.example", "X-Forwarded-Host": "evil.example", "Accept": "text/html"}


@pytest.fixture
def prefixed(db_session):
    settings = Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, DATABASE_URL="sqlite://",
                        PUBLIC_URL="https://coach.example.org/clinic")  # fmt: skip
    with TestClient(make_test_app(db_session, settings), raise_server_exceptions=False) as client:
        yield client


def _local_urls(html: str) -> list[str]:
    return re.findall(r'(?:href|src)="([^"#]*)"', html)


def test_pages_prefix_every_url_with_the_public_path(prefixed, make_patient_with_therapist, auth_headers, exercise,
                                                     store):  # fmt: skip
    patient, therapist = make_patient_with_therapist()
    row = store(patient, exercise, T0, data=make_khs("squat", 1, seed=31))
    headers = auth_headers(therapist) | EVIL
    for path in ("/therapist", f"/therapist/patients/{patient.id}", f"/therapist/sessions/{row.id}",
                 f"/therapist/sessions/{row.id}/replay"):  # fmt: skip
        response = prefixed.get(path, headers=headers)
        assert response.status_code == 200, f"{path}: {response.status_code}"
        assert "evil.example" not in response.text, f"{path} used the request's Host"
        urls = _local_urls(response.text)
        assert urls, path
        bad = [u for u in urls if not u.startswith("/clinic/")]
        assert not bad, f"{path}: URLs outside /clinic/: {bad}"


def test_redirects_use_the_public_path(prefixed):
    response = prefixed.get("/therapist", headers=EVIL, follow_redirects=False)
    assert response.status_code == 303
    assert response.headers["location"] == "/clinic/?next=%2Fclinic%2Ftherapist"


def test_replay_page_without_login_is_401_with_a_sign_in_link(prefixed):
    response = prefixed.get("/therapist/sessions/1/replay", headers=EVIL)
    assert response.status_code == 401
    assert 'href="/clinic/?next=%2Fclinic%2Ftherapist%2Fsessions%2F1%2Freplay"' in response.text
    assert prefixed.get("/replay/viewer/", headers=EVIL).status_code == 401


def test_a_public_url_that_is_not_http_is_refused():
    with pytest.raises(ValueError, match="COACH_PUBLIC_URL must be an http"):
        Settings(PUBLIC_URL="coach.example.org/clinic")


def test_api_docs_load_every_file_from_the_app_under_the_public_path(prefixed):
    path = "/docs"
    response = prefixed.get(path, headers=EVIL)
    assert response.status_code == 200
    assert "evil.example" not in response.text
    urls = re.findall(r"""(?:href|src|url|spec-url)\s*[=:]\s*['"]([^'"]+)['"]""", response.text)
    assert any(u.endswith(".js") for u in urls) and "/clinic/openapi.json" in urls, urls
    bad = [u for u in urls if not u.startswith("/clinic/")]
    assert not bad, f"{path}: URLs outside the app's /clinic/: {bad}"  # no CDN, no unprefixed path
    for url in urls:  # each one answers through the app (the proxy strips /clinic)
        answer = prefixed.get(url.removeprefix("/clinic"))
        assert answer.status_code == 200, url
        assert answer.content, url


def test_api_docs_serve_only_their_own_files(prefixed):
    assert (
        prefixed.get("/static/vendor/api-docs/swagger-ui-bundle.js")
        .headers["content-type"]
        .startswith("text/javascript")
    )
    for name in ("core.py", "..%2F__init__.py", "%2E%2E/consts.py", "nothing.js", "redoc.standalone.js"):
        assert prefixed.get(f"/static/vendor/api-docs/{name}").status_code == 404, name


def test_openapi_servers_name_the_public_path(prefixed, client):
    assert prefixed.get("/openapi.json").json()["servers"] == [{"url": "/clinic"}]
    assert "servers" not in client.get("/openapi.json").json()  # served at /: the default server "/"
