"""The OpenAPI schema is complete for REST clients: every JSON body an operation takes or returns has an example."""

from __future__ import annotations

from typing import Any


def _has_example(schema: dict[str, Any], components: dict[str, Any]) -> bool:
    ref = schema.get("$ref") or schema.get("items", {}).get("$ref")
    if ref is None:
        return True  # plain JSON (e.g. a list of strings) or a binary body
    component = components[ref.rsplit("/", 1)[-1]]
    if "examples" in component or "example" in component:
        return True
    properties = component.get("properties", {}).values()
    if any("examples" in p or "example" in p for p in properties):
        return True
    return "items" in component.get("properties", {}) and _has_example(component["properties"]["items"], components)


def test_every_json_body_has_an_example(client):
    schema = client.get("/openapi.json").json()
    components = schema["components"]["schemas"]
    missing = []
    for path, operations in schema["paths"].items():
        for method, op in operations.items():
            bodies = [("request", op.get("requestBody", {}).get("content", {}).get("application/json"))]
            bodies += [(code, r.get("content", {}).get("application/json")) for code, r in op["responses"].items()]
            for what, content in bodies:
                if content is not None and "example" not in content and not _has_example(content["schema"], components):
                    missing.append(f"{method.upper()} {path} {what}")
    assert not missing, missing


def test_errors_use_the_error_model(client):
    schema = client.get("/openapi.json").json()
    for path, operations in schema["paths"].items():
        for method, op in operations.items():
            for code, response in op["responses"].items():
                if code.startswith(("4", "5")) and "content" in response:
                    ref = response["content"]["application/json"]["schema"].get("$ref", "")
                    assert ref.endswith("/ErrorOut"), f"{method.upper()} {path} {code}: {ref}"
