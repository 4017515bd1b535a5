"""The pinned browser assets served from the app's own origin, one directory of kinect_agent/vendor/lock.json's
"serve" table at /static/vendor/<directory>/: MediaPipe Tasks Vision's WebAssembly runtime and the BlazePose `.task`
models (mediapipe/), plotly.js for the pages' charts (plotly/). Exactly the files named there, as installed
(hash-checked) by `python -m kinect_agent.vendor.install`. Public like the other static files: they are published
packages, not patient data.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from fastapi import APIRouter
from fastapi.responses import FileResponse, JSONResponse, Response

from kinect_agent.vendor import INSTALL_HINT, served_directories, served_files

PREFIX = "/static/vendor/"
MEDIA_TYPES = {
    ".mjs": "text/javascript; charset=utf-8",
    ".js": "text/javascript; charset=utf-8",
    ".wasm": "application/wasm",  # what WebAssembly.instantiateStreaming requires
    ".task": "application/octet-stream",
}
CACHE = {"Cache-Control": "public, max-age=86400"}  # pinned versions: a file's bytes change only with lock.json

router = APIRouter(include_in_schema=False)


def _asset_route(directory: str, served: dict[str, Path]) -> Callable[[str], Response]:
    def vendor_asset(path: str) -> Response:
        """Returns one served asset; 404 for any other path, 503 naming the install command when it is missing."""
        file = served.get(path)
        if file is None:
            return Response(status_code=404)
        if not file.is_file():
            detail = f"the asset {directory}/{path} is not installed on this server: {INSTALL_HINT}"
            return JSONResponse({"error": "AssetNotInstalled", "detail": detail}, status_code=503)
        return FileResponse(file, media_type=MEDIA_TYPES[file.suffix], headers=CACHE)

    return vendor_asset


for _directory in served_directories():
    _route = _asset_route(_directory, served_files(_directory))
    router.add_api_route(f"{PREFIX}{_directory}/{{path:path}}", _route, methods=["GET"], name=f"vendor_{_directory}")
