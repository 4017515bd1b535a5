"""The methods each API path answers, those of the OpenAPI document, so that the API and its document agree on
them: the Allow header of 405 and OPTIONS, and a 405 for a method the document does not give a path it spells out
(PATCH /users/me is 405 for every caller, not a 403 or 422 of the template /users/{user_id} that also matches)."""

from __future__ import annotations

from fastapi import FastAPI
from fastapi.routing import APIRoute, iter_route_contexts
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
            (compile_path(path)[0], methods, "{" not in path) for path, methods in documented_methods(app).items()
        ]
    path = connection.url.path.removeprefix(connection.scope.get("root_path", ""))
    matches = [(found, literal) for regex, found, literal in app.state.path_methods if regex.match(path)]
    if any(literal for _, literal in matches):
        matches = [(found, literal) for found, literal in matches if literal]
    methods = set().union(*(found for found, _ in matches))
    return sorted(methods | {"OPTIONS"}) if methods else []


def documented_methods(app: FastAPI) -> dict[str, set[str]]:
    """Returns {path: methods} of the OpenAPI document's paths, read from the routes the document is made of (the
    routes in the schema, by their path format, as fastapi.openapi.utils.get_openapi reads them) rather than by
    building the document: a new app's first request would otherwise build the whole document (0.2-0.5 s).
    tests/backend/test_allowed_methods.py holds the two equal."""
    paths: dict[str, set[str]] = {}
    for route in iter_route_contexts(app.routes):  # included routers' routes with their prefixes, as get_openapi
        if isinstance(route.original_route, APIRoute) and route.include_in_schema and route.path_format:
            paths.setdefault(route.path_format, set()).update(method.upper() for method in route.methods or ())
    return paths


async def refuse_undocumented_method(connection: HTTPConnection) -> None:
    """Raises 405 (before any other check of the request) when a route took a method that the OpenAPI document
    does not give the path: a template's route matching a path the document spells out with other methods."""
    if connection.scope["type"] != "http":
        return
    allowed = allowed_methods(connection.app, connection)
    if allowed and connection.scope["method"] not in allowed:
        raise HTTPException(405, "Method Not Allowed")
