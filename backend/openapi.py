"""The API's OpenAPI document: FastAPI's, with every error answer as {"error", "detail"} (ErrorOut), the answers
every operation can give before its route runs, and the security schemes (bearer token, login cookie)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from fastapi import FastAPI
from fastapi.openapi.utils import get_openapi

from backend.schemas import ErrorOut


def _error_answer(description: str, error: str, detail: str) -> dict[str, Any]:
    return {
        "description": description,
        "content": {
            "application/json": {
                "schema": {"$ref": "#/components/schemas/ErrorOut"},
                "example": {"error": error, "detail": detail},
            }
        },
    }


def _document_request_checks(schema: dict[str, Any]) -> None:
    """Adds to every operation the answers that come before its route (backend.request_limits, the database)."""
    for path in schema.get("paths", {}).values():
        for method, op in path.items():
            responses = op.setdefault("responses", {})
            nul = _error_answer("InvalidInput", "InvalidInput", "the URL contains a NUL character")
            responses.setdefault("400", nul)
            if "requestBody" in op:
                json_body = "application/json" in op["requestBody"].get("content", {})
                responses.setdefault("413", _error_answer("RequestTooLarge", "RequestTooLarge" if json_body else
                                                          "SessionTooLarge", "the body is over the limit"))  # fmt: skip
                responses.setdefault("422", _error_answer("InvalidInput", "InvalidInput",
                                                          "body: JSON text must be UTF-8; byte 3 is not"))  # fmt: skip
            if method.upper() not in ("GET", "HEAD"):
                responses.setdefault(
                    "503",
                    _error_answer(
                        "DatabaseBusy (another write holds the lock) or ServerBusy (no database slot came free)",
                        "DatabaseBusy",
                        "the database is busy with another write; retry in a second",
                    ),
                )
            else:  # backend.db_slots
                responses.setdefault("503", _error_answer("ServerBusy: no database slot came free", "ServerBusy",
                                                          "no database connection came free within 30 s; retry in a "
                                                          "few seconds"))  # fmt: skip


NO_NUL = r"^[^\x00]*$"  # backend.request_limits refuses a NUL character in the URL (400) and in JSON text (422)


def _document_no_nul(schema: dict[str, Any]) -> None:
    """Gives every text the client sends (parameters and request bodies, with the components they refer to) the
    pattern NO_NUL unless it has a pattern, a fixed set of values or binary content already, so that the document
    says what the server enforces."""
    components = schema.get("components", {}).get("schemas", {})
    done: set[str] = set()

    def visit(node: object) -> None:
        if isinstance(node, list):
            for item in node:
                visit(item)
        if not isinstance(node, dict):
            return
        name = node.get("$ref", "").removeprefix("#/components/schemas/")
        if name in components and name not in done:
            done.add(name)
            visit(components[name])
        if (
            node.get("type") == "string"
            and not {"pattern", "enum", "const"} & node.keys()
            and (node.get("format") != "binary")
        ):
            node["pattern"] = NO_NUL
        for value in node.values():
            visit(value)

    for operations in schema.get("paths", {}).values():
        for op in operations.values():
            visit(op.get("parameters", []))
            visit(op.get("requestBody", {}))


def _document_body_rules(schema: dict[str, Any]) -> None:
    """Names, in the 422 answer of every operation whose JSON body schema lists x-body-rules (backend.schemas.BodyRule:
    rules JSON Schema cannot state), each rule's refusal as an example beside the schema's own, so the document says
    which well-formed bodies are answered 422."""
    components = schema.get("components", {}).get("schemas", {})
    for path in schema.get("paths", {}).values():
        for op in path.values():
            body = op.get("requestBody", {}).get("content", {}).get("application/json", {}).get("schema", {})
            name = body.get("$ref", "").removeprefix("#/components/schemas/")
            rules = components.get(name, {}).get("x-body-rules", [])
            if not rules or "422" not in op.get("responses", {}):
                continue
            content = op["responses"]["422"]["content"]["application/json"]
            examples = {"ValidationError": {"summary": "the body does not follow the schema",
                                            "value": content.pop("example")}}  # fmt: skip
            for rule in rules:
                examples[rule["name"]] = {"summary": f"breaks a rule of the body: {rule['rule']}",
                                          "value": {"error": "ValidationError", "detail": rule["detail"]}}  # fmt: skip
            content["examples"] = examples
            op["responses"]["422"]["description"] = (
                "ValidationError: the body does not follow the schema, or breaks one of its x-body-rules: "
                + "; ".join(f"{r['name']} ({r['rule']})" for r in rules)
            )


def openapi_builder(app: FastAPI) -> Callable[[], dict[str, Any]]:
    """Returns app.openapi: FastAPI's document with the error body ErrorOut on every error answer, the answers
    given before any route (_document_request_checks) and the two security schemes."""

    def build() -> dict[str, Any]:
        if app.openapi_schema:
            return app.openapi_schema
        root = app.state.settings.root_path  # the configured prefix, so that "Try it out" calls the API through it
        schema = get_openapi(title=app.title, version=app.version, description=app.description, routes=app.routes,
                             servers=[{"url": root}] if root else None)  # fmt: skip
        components = schema.setdefault("components", {}).setdefault("schemas", {})
        components["ErrorOut"] = ErrorOut.model_json_schema(ref_template="#/components/schemas/{model}")
        example = {"error": "ValidationError", "detail": "body.email: Field required"}
        for path in schema.get("paths", {}).values():
            for op in path.values():
                responses = op.get("responses", {})
                if "422" in responses:
                    responses["422"] = {
                        "description": "ValidationError",
                        "content": {
                            "application/json": {
                                "schema": {"$ref": "#/components/schemas/ErrorOut"},
                                "example": example,
                            }
                        },
                    }
        _document_body_rules(schema)
        _document_request_checks(schema)
        _document_no_nul(schema)
        components.pop("HTTPValidationError", None)
        components.pop("ValidationError", None)
        schema.setdefault("components", {})["securitySchemes"] = {
            "bearer": {"type": "http", "scheme": "bearer", "description": "API token khc_... or device token khd_..."},
            "cookie": {"type": "apiKey", "in": "cookie", "name": "coach_session"},
        }
        schema["security"] = [{"bearer": []}, {"cookie": []}]
        app.openapi_schema = schema
        return schema

    return build
