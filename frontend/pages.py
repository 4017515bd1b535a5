"""HTML routes of the web pages (excluded from the OpenAPI schema) and their static files.

The pages check who is logged in (the same login cookie the API uses) only to pick the page: no login sends the
browser to the login page, a wrong role gets a 403 page. Every piece of data comes from the API, fetched by the
page scripts.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Annotated
from urllib.parse import quote

from fastapi import APIRouter, Depends, Request
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, RedirectResponse, Response
from fastapi.templating import Jinja2Templates

from backend.deps import Caller, DbSession, optional_caller, require_patient_access
from backend.exceptions import Forbidden, InvalidSessionFile, NotAuthenticated
from backend.schemas import IdPath
from kinect_agent.formats.session_file import SessionFileError

HERE = Path(__file__).resolve().parent
STATIC = HERE / "static"
PLOTLY_JS = Path(importlib.util.find_spec("plotly").submodule_search_locations[0]) / "package_data" / "plotly.min.js"
templates = Jinja2Templates(directory=str(HERE / "templates"))
router = APIRouter(include_in_schema=False)

OptionalCaller = Annotated[Caller | None, Depends(optional_caller)]
THERAPIST_ROLES = ("therapist", "admin")
_MEDIA = {".css": "text/css; charset=utf-8", ".js": "text/javascript; charset=utf-8", ".svg": "image/svg+xml"}
_NO_STORE = {"Cache-Control": "no-store"}


def home_for(role: str) -> str:
    """Returns the page a user of this role starts on."""
    return "/patient" if role == "patient" else "/therapist"


def _page(request: Request, name: str, caller: Caller | None, status_code: int = 200, **context) -> HTMLResponse:
    user = caller.user if caller is not None else None
    context |= {"user": user, "home": home_for(user.role) if user is not None else "/"}
    return templates.TemplateResponse(request, name, context, status_code=status_code, headers=_NO_STORE)


def _gate(request: Request, caller: Caller | None, roles: tuple[str, ...]) -> Response | None:
    """Returns a redirect to the login page (not logged in) or a 403 page (wrong role); None lets the page show."""
    if caller is None or caller.user is None:
        target = request.url.path + (f"?{request.url.query}" if request.url.query else "")
        return RedirectResponse(f"/?next={quote(target, safe='')}", status_code=303)
    if caller.user.role not in roles:
        return _page(request, "error.html", caller, status_code=403, title="Not for this account",
                     message="This page is for therapists. Your own page is one click away.")  # fmt: skip
    return None


@router.get("/", response_class=HTMLResponse)
def login_page(request: Request, caller: OptionalCaller) -> Response:
    """Shows the login form (a logged-in user is sent to their start page unless ?next= asks otherwise)."""
    if caller is not None and caller.user is not None and "next" not in request.query_params:
        return RedirectResponse(home_for(caller.user.role), status_code=303)
    return _page(request, "login.html", None)


@router.get("/patient", response_class=HTMLResponse)
def patient_page(request: Request, caller: OptionalCaller) -> Response:
    """Shows the patient's feedback screen (therapists are sent to their dashboard)."""
    if caller is not None and caller.user is not None and caller.user.role in THERAPIST_ROLES:
        return RedirectResponse("/therapist", status_code=303)
    return _gate(request, caller, ("patient",)) or _page(request, "patient.html", caller)


@router.get("/therapist", response_class=HTMLResponse)
def therapist_page(request: Request, caller: OptionalCaller) -> Response:
    """Shows the therapist's dashboard of assigned patients."""
    return _gate(request, caller, THERAPIST_ROLES) or _page(request, "therapist.html", caller)


@router.get("/therapist/patients/{patient_id}", response_class=HTMLResponse)
def patient_detail_page(patient_id: IdPath, request: Request, caller: OptionalCaller) -> Response:
    """Shows one patient for a therapist: progress plots, sessions, suggestions to review, a note form."""
    return _gate(request, caller, THERAPIST_ROLES) or _page(
        request, "patient_detail.html", caller, patient_id=patient_id
    )


@router.get("/therapist/sessions/{session_id}/replay", response_class=HTMLResponse)
def replay_page(session_id: IdPath, request: Request, caller: OptionalCaller) -> Response:
    """Shows the 3D replay page of one session (the viewer itself is started by the replay API call)."""
    return _gate(request, caller, THERAPIST_ROLES) or _page(request, "replay.html", caller, session_id=session_id)


@router.get("/therapist/sessions/{session_id}/replay/viewer")
def replay_viewer(session_id: IdPath, request: Request, caller: OptionalCaller, db_session: DbSession) -> JSONResponse:
    """Starts (or reuses) the 3D viewer of a session and returns its address: {"url", "frames"}."""
    from backend.sessions import service
    from frontend.replay import replays

    if caller is None or caller.user is None:
        raise NotAuthenticated("not logged in")
    if caller.user.role not in THERAPIST_ROLES:
        raise Forbidden("the 3D replay is for therapists")
    patient_id = service.session_patient(db_session=db_session, session_id=session_id)
    require_patient_access(patient_id, caller=caller, db_session=db_session)
    try:
        viewer = replays.open(session_id, lambda: service.session_file(db_session=db_session, session_id=session_id))
    except SessionFileError as exc:
        raise InvalidSessionFile(f"the stored file of session {session_id} cannot be replayed: {exc}") from None
    host = request.url.hostname or "127.0.0.1"
    return JSONResponse({"url": f"{request.url.scheme}://{host}:{viewer.port}/", "frames": viewer.n_frames},
                        headers=_NO_STORE)  # fmt: skip


@router.get("/static/vendor/plotly.min.js")
def plotly_js() -> Response:
    """Returns plotly.js as shipped inside the pinned `plotly` wheel (the charting library of the pages)."""
    return FileResponse(PLOTLY_JS, media_type=_MEDIA[".js"], headers={"Cache-Control": "public, max-age=86400"})


@router.get("/static/{name}")
def static_file(name: str) -> Response:
    """Returns one of the pages' static files (css, js)."""
    path = (STATIC / name).resolve()
    if path.parent != STATIC or path.suffix not in _MEDIA or not path.is_file():
        return Response(status_code=404)
    return FileResponse(path, media_type=_MEDIA[path.suffix], headers={"Cache-Control": "no-cache"})
