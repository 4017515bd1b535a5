"""The pinned pose assets (MediaPipe Tasks Vision's WebAssembly runtime and the BlazePose `.task` models) served at
/static/vendor/mediapipe/ from the app's own origin: exactly the files named in kinect_agent/vendor/lock.json's
"serve" table, as installed (hash-checked) by `python -m kinect_agent.vendor.install`. Public like the other static
files: they are published packages, not patient data.
"""

from __future__ import annotations

from pathlib import Path

from fastapi import APIRouter
from fastapi.responses import FileResponse, JSONResponse, Response

from kinect_agent.vendor import INSTALL_HINT, served_files

PREFIX = "/static/vendor/mediapipe/"
MEDIA_TYPES = {
    ".mjs": "text/javascript; charset=utf-8",
    ".js": "text/javascript; charset=utf-8",
    ".wasm": "application/wasm",  # what WebAssembly.instantiateStreaming requires
    ".task": "application/octet-stream",
}
CACHE = {"Cache-Control": "public, max-age=86400"}  # pinned versions: a file's bytes change only with lock.json

router = APIRouter(include_in_schema=False)
_SERVED: dict[str, Path] = served_files()


@router.get(PREFIX + "{path:path}")
def mediapipe_asset(path: str) -> Response:
    """Returns one served pose asset; 404 for any other path, 503 naming the install command when it is missing."""
    file = _SERVED.get(path)
    if file is None:
        return Response(status_code=404)
    if not file.is_file():
        detail = f"the pose asset {path} is not installed on this server: {INSTALL_HINT}"
        return JSONResponse({"error": "AssetNotInstalled", "detail": detail}, status_code=503)
    return FileResponse(file, media_type=MEDIA_TYPES[file.suffix], headers=CACHE)
