"""The API's documentation page, /docs (Swagger UI), served whole by the app on its own origin.

FastAPI's own pages load their scripts from a CDN and ask for /openapi.json at the server's root: a clinic network
without internet access, or a reverse proxy with a path prefix (COACH_PUBLIC_URL https://coach.example.org/clinic),
breaks them. Here every URL it uses starts with the configured prefix (never taken from the request) and the files
come from the pinned `fastapi-offline` wheel (Swagger UI and a favicon). No /redoc:
ReDoc fetches its logo from its vendor's CDN whatever it is told.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

from fastapi import APIRouter, FastAPI, Request
from fastapi.openapi.docs import get_swagger_ui_html, get_swagger_ui_oauth2_redirect_html
from fastapi.responses import FileResponse, HTMLResponse, Response

_SPEC = importlib.util.find_spec("fastapi_offline")
if _SPEC is None or not _SPEC.submodule_search_locations:
    raise ModuleNotFoundError("the package fastapi_offline is not installed", name="fastapi_offline")
ASSETS = Path(_SPEC.submodule_search_locations[0]) / "static"
FILES = {  # the URL's file name -> media type; the only files served from ASSETS
    "swagger-ui-bundle.js": "text/javascript; charset=utf-8",
    "swagger-ui.css": "text/css; charset=utf-8",
    "favicon.png": "image/png",
}
ASSET_PATH = "/static/vendor/api-docs"
router = APIRouter(include_in_schema=False)


def _root(request: Request) -> str:
    return request.app.state.settings.root_path


@router.get("/docs")
def swagger_ui(request: Request) -> HTMLResponse:
    """Returns Swagger UI for the OpenAPI document, its files and the document under the configured prefix."""
    root, app = _root(request), request.app
    return get_swagger_ui_html(
        openapi_url=root + app.openapi_url,
        title=f"{app.title} - API",
        oauth2_redirect_url=root + app.swagger_ui_oauth2_redirect_url,
        swagger_js_url=f"{root}{ASSET_PATH}/swagger-ui-bundle.js",
        swagger_css_url=f"{root}{ASSET_PATH}/swagger-ui.css",
        swagger_favicon_url=f"{root}{ASSET_PATH}/favicon.png",
    )


@router.get("/docs/oauth2-redirect")
def swagger_ui_redirect() -> HTMLResponse:
    """Returns Swagger UI's OAuth2 redirect page (part of Swagger UI; the API itself uses no OAuth2 flow)."""
    return get_swagger_ui_oauth2_redirect_html()


@router.get(ASSET_PATH + "/{name}")
def asset(name: str) -> Response:
    """Returns one of the documentation page's files (FILES), or 404."""
    if name not in FILES:
        return Response(status_code=404)
    return FileResponse(ASSETS / name, media_type=FILES[name], headers={"Cache-Control": "public, max-age=86400"})


def mount(app: FastAPI) -> None:
    """Serves the documentation page (the app must be made with docs_url=None and redoc_url=None)."""
    app.include_router(router)
