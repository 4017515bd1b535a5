"""The OpenAPI document states the rules the server enforces on input: no NUL character in any text the client
sends (refused by backend.request_limits), the e-mail format of a new user, and a staff upload's patient_id."""

from __future__ import annotations

import re

import pytest

NUL_TEXT = "ana\x00@example.org"


def _strings(node, where="#"):
    """Yields (where, schema) for every string schema in a part of the document."""
    if isinstance(node, dict):
        if node.get("type") == "string":
            yield where, node
        for key, value in node.items():
            yield from _strings(value, f"{where}/{key}")
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from _strings(value, f"{where}/{i}")


def _request_side(document: dict) -> list[tuple[str, dict]]:
    """Returns the string schemas of every parameter and request body, following $refs into the components."""
    components = document["components"]["schemas"]
    found, seen = [], set()

    def visit(node, where):
        if isinstance(node, dict):
            ref = node.get("$ref", "")
            if ref.startswith("#/components/schemas/") and ref not in seen:
                seen.add(ref)
                visit(components[ref.rpartition("/")[2]], ref)
            if node.get("type") == "string":
                found.append((where, node))
            for key, value in node.items():
                visit(value, f"{where}/{key}")
        elif isinstance(node, list):
            for value in node:
                visit(value, where)

    for path, operations in document["paths"].items():
        for method, op in operations.items():
            visit(op.get("parameters", []), f"{method} {path} parameters")
            visit(op.get("requestBody", {}), f"{method} {path} body")
    return found


def test_no_text_the_client_sends_may_hold_a_nul_character(client):
    strings = _request_side(client.get("/openapi.json").json())
    assert len(strings) > 30
    for where, schema in strings:
        if "enum" in schema or "const" in schema or schema.get("format") == "binary":  # a session file's bytes
            continue
        assert "pattern" in schema, f"{where}: {schema} says nothing of NUL characters"
        assert not re.search(schema["pattern"], NUL_TEXT), f"{where}: pattern {schema['pattern']!r} allows NUL"


EMAILS = ["ana@example.org", "Ana.Silva+pt@clinic.example.org", "a@b", "ana example@x.org", "@example.org", "ana@",
          "ana@@example.org", "ana@example", "ana@.org", "a" * 310 + "@example.org"]  # fmt: skip


@pytest.mark.parametrize("email", EMAILS)
def test_the_email_pattern_is_the_servers_rule(client, make_user, auth_headers, email):
    schema = client.get("/openapi.json").json()["components"]["schemas"]["UserCreate"]["properties"]["email"]
    documented = re.search(schema["pattern"], email) is not None and len(email) <= schema["maxLength"]
    body = {"email": email, "role": "patient", "password": "correct horse battery"}
    response = client.post("/api/v1/users", json=body, headers=auth_headers(make_user("admin")))
    assert response.status_code in (201, 422), response.text
    assert (response.status_code == 201) == documented, (email, response.text)


def test_a_staff_upload_without_patient_id_is_the_documented_403(client, make_patient_with_therapist, auth_headers,
                                                                  db_session):  # fmt: skip
    from tests.backend.khs_files import make_khs

    _, therapist = make_patient_with_therapist()
    headers = {**auth_headers(therapist), "Content-Type": "application/octet-stream"}
    db_session.commit()
    response = client.post("/api/v1/sessions", content=make_khs(), headers=headers)
    assert response.status_code == 403, response.text  # the request is well formed; the caller has no own sessions
    detail = "a therapist or admin uploads for a patient: name them with ?patient_id="
    assert response.json() == {"error": "PatientIdRequired", "detail": detail}
    op = client.get("/openapi.json").json()["paths"]["/api/v1/sessions"]["post"]
    assert "PatientIdRequired" in op["responses"]["403"]["content"]["application/json"]["examples"]
    patient_id = next(p for p in op["parameters"] if p["name"] == "patient_id")
    assert "required when a therapist or admin uploads (403 PatientIdRequired)" in patient_id["description"]


def test_the_effort_in_halves_is_in_the_schema(client):
    effort = client.get("/openapi.json").json()["components"]["schemas"]["FeelingIn"]["properties"]["effort"]
    number = next(s for s in effort["anyOf"] if s.get("type") == "number")
    assert number["multipleOf"] == 0.5, effort


def test_a_pairing_code_that_pairs_nothing_is_a_refused_credential_not_bad_input(client):
    response = client.post("/api/v1/devices/pair", json={"code": "0000"})  # well formed, as the schema says
    assert response.status_code == 403, response.text
    assert response.json()["error"] == "PairingCodeInvalid"
    op = client.get("/openapi.json").json()["paths"]["/api/v1/devices/pair"]["post"]
    assert "PairingCodeInvalid" in op["responses"]["403"]["content"]["application/json"]["examples"]
