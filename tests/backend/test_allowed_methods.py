"""The methods each path answers are the OpenAPI document's: read from the routes (backend.allowed_methods), they
equal the document's paths and operations."""

from __future__ import annotations

from backend.allowed_methods import documented_methods


def test_the_methods_read_from_the_routes_are_the_documents(app) -> None:
    document = {path: {method.upper() for method in ops} for path, ops in app.openapi()["paths"].items()}
    assert documented_methods(app) == document
    assert len(document) > 50 and document["/api/v1/users/me"] == {"GET"}  # /users/{user_id} also takes PATCH


def test_a_method_the_document_does_not_give_a_spelled_out_path_is_405(client) -> None:
    answer = client.patch("/api/v1/users/me", json={})
    assert answer.status_code == 405 and "PATCH" not in answer.headers["allow"]
