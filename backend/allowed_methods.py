"""The methods each API path answers, read from the OpenAPI document, so that the API and its document agree on
them: the Allow header of 405 and OPTIONS, and a 405 for a method the document does not give a path it spells out
(PATCH /users/me is 405 for every caller, not a 403 or 422 of the template /users/{user_id} that also matches)."""

from __future__ import annotations

from fastapi import FastAPI
from starlette.exceptions import HTTPException
from starlette.requests import HTTPConnection
from starlette.routing import compile_path


def allowed_methods(app: FastAPI, connection: HTTPConnection) -> list[str]:
    """Returns the methods the OpenAPI document gives the request's path (Starlette's Allow names only the first
    matching route's), with OPTIONS, which the app answers for every path; empty for paths it does not list. A path
    spelled out in the document (/devices/me) has its own methods only, not those of a template that would also
    match it (/devices/{device_id})."""
    if not hasattr(app.state, "path_methods"):
        app.state.path_methods = [
            (compile_path(path)[0], {method.upper() for method in operations}, "{" not in path)
            for path, operations in app.openapi().get("paths", {}).items()
        ]
    path = connection.url.path.removeprefix(connection.scope.get("root_path", ""))
    matches = [(found, literal) for regex, found, literal in app.state.path_methods if regex.match(path)]
    if any(literal for _, literal in matches):
        matches = [(found, literal) for found, literal in matches if literal]
    methods = set().union(*(found for found, _ in matches))
    return sorted(methods | {"OPTIONS"}) if methods else []


async def refuse_undocumented_method(connection: HTTPConnection) -> None:
    """Raises 405 (before any other check of the request) when a route took a method that the OpenAPI document
    does not give the path: a template's route matching a path the document spells out with other methods."""
    if connection.scope["type"] != "http":
        return
    allowed = allowed_methods(connection.app, connection)
    if allowed and connection.scope["method"] not in allowed:
        raise HTTPException(405, "Method Not Allowed")
