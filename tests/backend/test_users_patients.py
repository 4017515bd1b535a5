"""Admin user management, therapist assignment, who sees which patients, the audit log, health."""

from __future__ import annotations


def test_admin_creates_lists_and_deactivates(client, make_user, auth_headers):
    admin = make_user("admin")
    headers = auth_headers(admin)
    body = {"email": "New@Example.org", "role": "therapist", "password": "0123456789ab", "full_name": "N"}
    r = client.post("/api/v1/users", json=body, headers=headers)
    assert r.status_code == 201 and r.json()["email"] == "new@example.org"
    dup = client.post("/api/v1/users", json=body, headers=headers)
    assert dup.status_code == 409 and dup.json()["error"] == "EmailAlreadyRegistered"
    page = client.get("/api/v1/users?role=therapist&limit=1", headers=headers).json()
    assert page["total"] == 1 and page["limit"] == 1 and len(page["items"]) == 1
    uid = r.json()["id"]
    assert client.patch(f"/api/v1/users/{uid}", json={"is_active": False}, headers=headers).json()["is_active"] is False
    own = client.patch(f"/api/v1/users/{admin.id}", json={"is_active": False}, headers=headers)
    assert own.status_code == 403


def test_deactivation_revokes_api_tokens(client, make_user, auth_headers):
    admin, user = make_user("admin"), make_user("therapist")
    user_headers = auth_headers(user)
    client.patch(f"/api/v1/users/{user.id}", json={"is_active": False}, headers=auth_headers(admin))
    assert client.get("/api/v1/users/me", headers=user_headers).status_code == 401


def test_assignment_controls_what_a_therapist_sees(client, make_user, auth_headers):
    admin, therapist = make_user("admin"), make_user("therapist")
    p1, p2 = make_user("patient"), make_user("patient")
    t_headers, a_headers = auth_headers(therapist), auth_headers(admin)
    assert client.get("/api/v1/patients", headers=t_headers).json()["total"] == 0
    r = client.put(f"/api/v1/patients/{p1.id}/therapists/{therapist.id}", headers=a_headers)
    assert r.status_code == 204
    listed = client.get("/api/v1/patients", headers=t_headers).json()
    assert [p["id"] for p in listed["items"]] == [p1.id] and listed["items"][0]["therapist_ids"] == [therapist.id]
    assert client.get(f"/api/v1/patients/{p2.id}", headers=t_headers).status_code == 404
    bad = client.put(f"/api/v1/patients/{p1.id}/therapists/{p2.id}", headers=a_headers)
    assert bad.status_code == 404 and bad.json()["error"] == "TherapistNotFound"
    assert client.delete(f"/api/v1/patients/{p1.id}/therapists/{therapist.id}", headers=a_headers).status_code == 204
    assert client.get(f"/api/v1/patients/{p1.id}", headers=t_headers).status_code == 404


def test_patient_sees_only_self_and_reads_are_audited(client, make_user, auth_headers):
    admin, patient = make_user("admin"), make_user("patient")
    listed = client.get("/api/v1/patients", headers=auth_headers(patient)).json()
    assert [p["id"] for p in listed["items"]] == [patient.id]
    client.get(f"/api/v1/patients/{patient.id}", headers=auth_headers(patient))
    audit = client.get(f"/api/v1/audit?patient_id={patient.id}", headers=auth_headers(admin)).json()
    actions = [(e["action"], e["actor_user_id"]) for e in audit["items"]]
    assert ("patient.read", patient.id) in actions and ("patient.list", patient.id) in actions
    assert client.get("/api/v1/audit", headers=auth_headers(patient)).status_code == 403


def test_missing_patient_is_404(client, make_user, auth_headers):
    r = client.get("/api/v1/patients/2147483000", headers=auth_headers(make_user("admin")))
    assert r.status_code == 404 and r.json() == {
        "error": "PatientNotFound",
        "detail": "patient 2147483000 does not exist",
    }


def test_healthz_and_version(client):
    assert client.get("/healthz").json() == {"status": "ok", "database": "ok"}
    assert client.get("/api/v1/version").json()["api"] == "v1"


def test_unknown_route_uses_error_body(client):
    r = client.get("/api/v1/nope")
    assert r.status_code == 404 and r.json()["error"] == "NotFound"


def test_openapi_documents_errors_with_examples(app):
    spec = app.openapi()
    op = spec["paths"]["/api/v1/patients/{patient_id}"]["get"]
    examples = op["responses"]["404"]["content"]["application/json"]["examples"]
    assert "PatientNotFound" in examples and "422" in op["responses"]
