"""The camera page and its landmarker's worker alone may compile WebAssembly ('wasm-unsafe-eval'); their connections
stay on this origin, which blocks MediaPipe's usage-metrics call to another site."""

from __future__ import annotations

import pytest

from backend.security_headers import CAMERA_POLICY, policy_for


def test_only_the_camera_page_allows_wasm(client):
    r = client.get("/patient/camera", follow_redirects=False)
    csp = r.headers["content-security-policy"]
    assert "'wasm-unsafe-eval'" in csp and "connect-src 'self';" in csp, csp
    assert "'unsafe-eval'" not in csp.replace("'wasm-unsafe-eval'", ""), csp
    for path in ("/patient", "/therapist", "/", "/static/camera_page.js", "/api/v1/camera/consent"):
        assert "wasm-unsafe-eval" not in client.get(path, follow_redirects=False).headers["content-security-policy"], (
            path
        )


def test_the_landmarker_worker_gets_the_camera_policy(client):
    """A worker runs under its own script's CSP, and the worker is what compiles the landmarker's WebAssembly."""
    r = client.get("/static/camera_pose_worker.js")
    assert r.status_code == 200 and "javascript" in r.headers["content-type"], r.headers
    assert r.headers["content-security-policy"] == CAMERA_POLICY


@pytest.mark.parametrize("path", ["/patient/camera/", "/patient/camera2", "/patient", "/static/camera_pose.js"])
def test_near_paths_get_the_page_policy(path):
    assert policy_for(path) != CAMERA_POLICY


def test_the_camera_page_needs_a_patient_login(client, make_user, auth_headers):
    assert client.get("/patient/camera", follow_redirects=False).status_code == 303
    therapist = make_user("therapist")
    r = client.get("/patient/camera", headers=auth_headers(therapist) | {"Accept": "text/html"}, follow_redirects=False)
    assert r.status_code in (303, 403), r.status_code
