"""Unknown addresses: an HTML page for browsers, the JSON error body for the API and other clients."""

from __future__ import annotations

import pytest

HTML = {"Accept": "text/html,application/xhtml+xml,application/xml;q=0.9,*/*;q=0.8"}


def test_browser_gets_an_html_404_page_with_a_way_home(client):
    r = client.get("/no/such/page", headers=HTML)
    assert r.status_code == 404
    assert r.headers["content-type"].startswith("text/html")
    assert '<html lang="en">' in r.text
    assert "<title>Page not found · Kinect Home Coach</title>" in r.text
    assert "<h1>Page not found</h1>" in r.text
    assert 'href="/"' in r.text and "Go to the start page" in r.text
    assert '<link rel="stylesheet" href="/static/app.css">' in r.text


@pytest.mark.parametrize("path", ["/api/v1/no-such-thing", "/api/nothing", "/api"])
def test_unknown_api_path_gets_json_even_from_a_browser(client, path):
    r = client.get(path, headers=HTML)
    assert r.status_code == 404
    assert r.json() == {"error": "NotFound", "detail": "Not Found"}


def test_client_not_asking_for_html_gets_json(client):
    r = client.get("/no/such/page", headers={"Accept": "application/json"})
    assert r.status_code == 404
    assert r.json() == {"error": "NotFound", "detail": "Not Found"}


def test_malformed_page_id_is_a_404_page_for_a_browser(client):
    r = client.get("/therapist/patients/not-a-number", headers=HTML)
    assert r.status_code == 404
    assert "Page not found" in r.text


def test_malformed_api_id_stays_a_json_validation_error(client, make_user, auth_headers):
    r = client.get("/api/v1/patients/not-a-number", headers=HTML | auth_headers(make_user("therapist")))
    assert r.status_code == 422
    assert r.json()["error"] == "ValidationError"


def test_wrong_method_on_a_page_keeps_the_allow_header(client):
    r = client.post("/therapist", headers=HTML)
    assert r.status_code == 405
    assert "text/html" in r.headers["content-type"] and r.headers["allow"] == "GET"


def test_another_therapists_patient_page_is_the_404_page(client, make_patient_with_therapist, make_user, auth_headers):
    patient, mine = make_patient_with_therapist()
    other = make_user("therapist")
    r = client.get(f"/therapist/patients/{patient.id}", headers=HTML | auth_headers(other))
    assert r.status_code == 404 and "<h1>Patient not found</h1>" in r.text and "Loading" not in r.text
    missing = client.get("/therapist/patients/999999", headers=HTML | auth_headers(other))
    assert missing.status_code == 404 and "<h1>Patient not found</h1>" in missing.text  # the same page: no hint
    assert client.get(f"/therapist/patients/{patient.id}", headers=HTML | auth_headers(mine)).status_code == 200
