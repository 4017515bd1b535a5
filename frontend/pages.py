"""HTML routes of the web pages (excluded from the OpenAPI schema) and their static files.

The pages check who is logged in (the same login cookie the API uses) only to pick the page: no login sends the
browser to the login page, a wrong role gets a 403 page. Every piece of data comes from the API, fetched by the
page scripts.
"""

from __future__ import annotations

import datetime as dt
import importlib.util
import re
from functools import lru_cache
from pathlib import Path
from typing import Annotated, Any
from urllib.parse import parse_qsl, quote

from fastapi import APIRouter, Depends, FastAPI, Request
from fastapi.responses import FileResponse, HTMLResponse, RedirectResponse, Response
from fastapi.templating import Jinja2Templates
from sqlalchemy.orm import Session

from backend.deps import Caller, DbSession, optional_caller, require_patient_access
from backend.exceptions import NotFound
from backend.i18n import (
    LANGUAGE_NAMES,
    LOCALES,
    N_,
    js_messages,
    negotiate,
    therapist_locales,
    therapist_translations,
    translations,
    translator,
)
from backend.records import report
from backend.reminders.service import UNSUBSCRIBE_PATH, patient_of_token, unsubscribe
from backend.reminders.times import zone_names
from backend.schemas import IdPath
from backend.users.models import User
from frontend import vendor_assets
from frontend.replay_viewer import viewer_html

HERE = Path(__file__).resolve().parent
STATIC = HERE / "static"


def _package_dir(name: str) -> Path:
    """Returns the folder of an installed package, without importing it."""
    spec = importlib.util.find_spec(name)
    if spec is None or not spec.submodule_search_locations:
        raise ModuleNotFoundError(f"the package {name} is not installed", name=name)
    return Path(spec.submodule_search_locations[0])


VISER_CLIENT = _package_dir("viser") / "client" / "build" / "index.html"


@lru_cache(maxsize=2 * len(LOCALES))
def templates_for(locale: str, therapist: bool = False) -> Jinja2Templates:
    """Returns the pages' templates in one language: Jinja's i18n extension with that locale's catalogue (for a
    therapist's page: the therapist domain's, then the shared messages')."""
    found = Jinja2Templates(directory=str(HERE / "templates"))
    found.env.add_extension("jinja2.ext.i18n")
    found.env.policies["ext.i18n.trimmed"] = True
    chosen = therapist_translations(locale) if therapist else translations(locale)
    # added to the Environment at run time by jinja2.ext.i18n; jinja2's types do not declare it
    found.env.install_gettext_translations(chosen, newstyle=True)  # type: ignore[attr-defined]
    return found


router = APIRouter(include_in_schema=False)

OptionalCaller = Annotated[Caller | None, Depends(optional_caller)]
THERAPIST_ROLES = ("therapist", "admin")
_MEDIA = {".css": "text/css; charset=utf-8", ".js": "text/javascript; charset=utf-8", ".svg": "image/svg+xml"}
_NO_STORE = {"Cache-Control": "no-store"}


def home_for(role: str) -> str:
    """Returns the page a user of this role starts on."""
    return "/patient" if role == "patient" else "/therapist"


def _root(request: Request) -> str:
    """Returns the configured path prefix of the app's URLs (from COACH_PUBLIC_URL, never from the request)."""
    return request.app.state.settings.root_path


def _here(request: Request) -> str:
    """Returns the address of this request as a path of the app's public URL (prefix, path, query): the ?next=
    a login comes back to."""
    return _root(request) + request.url.path + (f"?{request.url.query}" if request.url.query else "")


def page_locale(request: Request, user: User | None) -> str:
    """Returns the language of a page: a patient's chosen one, else the browser's (Accept-Language); a therapist's
    page: their chosen or their browser's language among the locales with a therapist catalogue (therapist.po; none
    yet, so English), see backend/i18n."""
    if user is not None and user.role in THERAPIST_ROLES:
        if user.locale in therapist_locales():
            return user.locale
        return negotiate(request.headers.get("accept-language"), therapist_locales())
    if user is not None and user.locale in LOCALES:
        return user.locale
    return negotiate(request.headers.get("accept-language"))


def _page(request: Request, name: str, caller: Caller | None, status_code: int = 200, locale: str | None = None,
          **context: Any) -> HTMLResponse:  # fmt: skip
    user = caller.user if caller is not None else None
    root = _root(request)
    locale = locale or page_locale(request, user)
    home = root + (home_for(user.role) if user is not None else "/")
    therapist = user is not None and user.role in THERAPIST_ROLES
    context = {"user": user, "home": home, "root": root, "locale": locale, "languages": LANGUAGE_NAMES,
               "i18n_messages": js_messages(locale, therapist)} | context  # fmt: skip
    return templates_for(locale, therapist).TemplateResponse(request, name, context, status_code=status_code,
                                                             headers=_NO_STORE)  # fmt: skip


_ERROR_PAGES = {
    404: (N_("Page not found"), N_("There is no page at this address. It may have moved, or the link has a typo.")),
    405: (N_("Not possible here"), N_("This address cannot be opened this way.")),
}


def mount(app: FastAPI) -> None:
    """Mounts the pages on the app, the one place that does: their routes, and the HTML page that answers a
    browser's error outside /api/ (app.state.error_page, which the app's error handlers call)."""
    app.include_router(router)
    app.include_router(vendor_assets.router)  # /static/vendor/: the pinned pose runtime and models, plotly.js
    app.state.error_page = browser_error_page


def browser_error_page(request: Request, status_code: int) -> HTMLResponse | None:
    """Returns the error page when a browser asked for a page (wants_html), else None (the API's JSON answers)."""
    return error_page(request, status_code) if wants_html(request) else None


def wants_html(request: Request) -> bool:
    """Returns whether an error should be answered with a page: a browser (Accept text/html) outside /api/."""
    path = request.url.path
    if path == "/api" or path.startswith("/api/"):
        return False
    return "text/html" in request.headers.get("accept", "")


def error_page(request: Request, status_code: int) -> HTMLResponse:
    """Returns the HTML page of an HTTP error (unknown URL and the like) with a link to the start page."""
    title, message = _ERROR_PAGES.get(status_code, (N_("Something went wrong"), N_("This page cannot be shown.")))
    return _error(
        request, None, status_code, title, message, page_id=f"error-{status_code}", link_text=N_("Go to the start page")
    )


def _error(
    request: Request, caller: Caller | None, status_code: int, title: str, message: str, **context: Any
) -> HTMLResponse:
    """Returns the error page, its title, message and link text (marked with N_) in the page's language."""
    user = caller.user if caller is not None else None
    t = translator(page_locale(request, user if user is None or user.role == "patient" else None))
    params = context.pop("params", {})
    link = context.get("link_text")
    if link is not None:
        context["link_text"] = t.gettext(link)
    return _page(request, "error.html", caller, status_code=status_code, locale=t.locale, title=t.gettext(title),
                 message=t.gettext(message, **params), **context)  # fmt: skip


def _gate(request: Request, caller: Caller | None, roles: tuple[str, ...]) -> Response | None:
    """Returns a redirect to the login page (not logged in) or a 403 page (wrong role); None lets the page show."""
    if caller is None or caller.user is None:
        return RedirectResponse(f"{_root(request)}/?next={quote(_here(request), safe='')}", status_code=303)
    if caller.user.role not in roles:
        return _error(
            request,
            caller,
            403,
            N_("Not for this account"),
            N_("This page is for therapists. Your own page is one click away."),
        )
    return None


@router.get("/", response_class=HTMLResponse)
def login_page(request: Request, caller: OptionalCaller) -> Response:
    """Shows the login form (a logged-in user is sent to their start page unless ?next= asks otherwise)."""
    if caller is not None and caller.user is not None and "next" not in request.query_params:
        return RedirectResponse(_root(request) + home_for(caller.user.role), status_code=303)
    return _page(request, "login.html", None)


@router.get("/patient", response_class=HTMLResponse)
def patient_page(request: Request, caller: OptionalCaller) -> Response:
    """Shows the patient's feedback screen (therapists are sent to their dashboard)."""
    if caller is not None and caller.user is not None and caller.user.role in THERAPIST_ROLES:
        return RedirectResponse(f"{_root(request)}/therapist", status_code=303)
    gate = _gate(request, caller, ("patient",))
    if gate is not None:
        return gate
    assert caller is not None and caller.user is not None  # _gate let a patient through
    settings = request.app.state.settings
    zone = caller.user.time_zone or settings.TIME_ZONE
    choices = time_zone_choices()
    return _page(request, "patient.html", caller, time_zones=choices if zone in choices else [zone, *choices],
                 time_zone=zone,
                 reminder_emails=caller.user.reminder_emails_off_at is None,
                 clinic_sends_emails=settings.reminder_emails)  # fmt: skip


@lru_cache(maxsize=1)
def time_zone_choices() -> list[str]:
    """Returns the IANA time zones a patient can choose on their page, sorted: the server's whole list (the one
    PATCH /patients/{id} checks), without the old aliases that are no Area/Location name ("EST5EDT", "GB")."""
    return sorted(z for z in zone_names() if "/" in z or z == "UTC")


@router.get("/patient/camera", response_class=HTMLResponse)
def camera_page(request: Request, caller: OptionalCaller) -> Response:
    """Shows the camera set of one exercise of the patient's plan (?item=<plan item id>): consent, placement check,
    the live count with this computer's camera, the saved result (frontend/static/camera_*.js); therapists are sent
    to their dashboard."""
    if caller is not None and caller.user is not None and caller.user.role in THERAPIST_ROLES:
        return RedirectResponse(f"{_root(request)}/therapist", status_code=303)
    return _gate(request, caller, ("patient",)) or _page(request, "camera.html", caller)


@router.get("/therapist", response_class=HTMLResponse)
def therapist_page(request: Request, caller: OptionalCaller) -> Response:
    """Shows the therapist's dashboard of assigned patients."""
    return _gate(request, caller, THERAPIST_ROLES) or _page(request, "therapist.html", caller)


@router.get("/admin/jobs", response_class=HTMLResponse)
def jobs_page(request: Request, caller: OptionalCaller) -> Response:
    """Shows the queue to admins: start a re-analysis (all sessions or one patient's) and follow it; the 403 page
    for anyone else."""
    gate = _gate(request, caller, THERAPIST_ROLES)
    if gate is not None:
        return gate
    if caller is None or caller.user is None or caller.user.role != "admin":
        return _error(request, caller, 403, N_("Not for this account"),
                      N_("This page is for the clinic's administrators."))  # fmt: skip
    return _page(request, "admin_jobs.html", caller)


@router.get("/therapist/patients/{patient_id}", response_class=HTMLResponse)
def patient_detail_page(
    patient_id: IdPath, request: Request, caller: OptionalCaller, db_session: DbSession
) -> Response:
    """Shows one patient for a therapist: progress plots, sessions, suggestions to review, a note form; the 404 page
    for a patient they may not see (another therapist's, or none: which of the two is not theirs to know)."""
    gate = _gate(request, caller, THERAPIST_ROLES)
    if gate is not None:
        return gate
    assert caller is not None  # _gate sent a signed-out browser to the login page
    try:
        require_patient_access(patient_id, caller=caller, db_session=db_session)
    except NotFound:
        return _error(
            request,
            caller,
            404,
            N_("Patient not found"),
            N_("There is no patient %(patient_id)s that you may see."),
            params={"patient_id": patient_id},
        )
    last = dt.datetime.now(dt.UTC).date()
    return _page(request, "patient_detail.html", caller, patient_id=patient_id,
                 report_from=(last - dt.timedelta(days=report.DEFAULT_DAYS - 1)).isoformat(),
                 report_to=last.isoformat())  # fmt: skip


def _visible_session(request: Request, caller: Caller, db_session: Session, session_id: int) -> int | Response:
    """Returns the patient id of session_id, or the 404 page when the caller may not see it (missing, or another
    person's: whether it exists is not theirs to know)."""
    from backend.sessions.service import missing, session_patient

    try:
        patient_id = session_patient(db_session=db_session, session_id=session_id)
        require_patient_access(patient_id, caller=caller, db_session=db_session, hidden_as=missing(session_id))
    except NotFound:
        return _error(
            request,
            caller,
            404,
            N_("Session not found"),
            N_("There is no session %(session_id)s that you may see."),
            params={"session_id": session_id},
        )
    return patient_id


@router.get("/therapist/sessions/{session_id}", response_class=HTMLResponse)
def session_page(session_id: IdPath, request: Request, caller: OptionalCaller, db_session: DbSession) -> Response:
    """Shows one session for a therapist: angle curves, repetitions, reach, data quality, processing; the 404 page
    for a session they may not see."""
    gate = _gate(request, caller, THERAPIST_ROLES)
    if gate is not None:
        return gate
    assert caller is not None  # _gate sent a signed-out browser to the login page
    found = _visible_session(request, caller, db_session, session_id)
    return found if isinstance(found, Response) else _page(request, "session.html", caller, session_id=session_id)


@router.get("/therapist/sessions/{session_id}/replay", response_class=HTMLResponse)
def replay_page(session_id: IdPath, request: Request, caller: OptionalCaller, db_session: DbSession) -> Response:
    """Shows the 3D replay of one session (viser's client on this origin playing the session's recording).

    Open to whoever may see the session: the patient's therapists, the patient, admins; anyone else gets the 404
    page of a session that is not there. No login: 401 page.
    """
    if caller is None or caller.user is None:
        return _sign_in_first(request)
    found = _visible_session(request, caller, db_session, session_id)
    if isinstance(found, Response):
        return found
    from backend.replay.service import stored_replay_key

    ready = stored_replay_key(db_session=db_session, session_id=session_id) is not None
    # not built yet: the page says it is being prepared (replay.js polls its state) and reloads once it is
    return _page(request, "replay.html", caller, session_id=session_id, patient_id=found, replay_ready=ready)


@router.get("/replay/viewer/", response_class=HTMLResponse)
def replay_viewer(request: Request, caller: OptionalCaller) -> Response:
    """Returns viser's own web client (bundled in the pinned viser wheel) in the reader's language where the app can
    say it (frontend/replay_viewer.py), for signed-in users; the replay page opens it with ?playbackPath= pointing to
    the session's recording in the API.

    Any other query is the 404 page: the client would fetch a recording from any URL in playbackPath, or connect
    to any server in ?websocket=, and run the JavaScript a recording carries (viser's RunJavascriptMessage) on
    this origin, with the signed-in user's cookie.
    """
    if caller is None or caller.user is None:
        return _sign_in_first(request)
    if not is_replay_recording(request, request.url.query):
        return error_page(request, 404)
    user = caller.user
    html = viewer_html(VISER_CLIENT, page_locale(request, user), user.role in THERAPIST_ROLES, _root(request))
    return HTMLResponse(html, headers={"Cache-Control": "private, no-cache"})


def is_replay_recording(request: Request, query: str) -> bool:
    """Returns whether a viewer query is exactly playbackPath=<the app's path of one session's replay>, optionally
    of one of its skeletons (?layer=raw or ?layer=filtered: the replay page's checkboxes)."""
    pairs = parse_qsl(query, keep_blank_values=True)
    if len(pairs) != 1 or pairs[0][0] != "playbackPath":
        return False
    path = re.escape(_root(request)) + r"/api/v1/sessions/[1-9][0-9]{0,9}/replay(\?layer=(raw|filtered))?"
    return re.fullmatch(path, pairs[0][1]) is not None


def _sign_in_first(request: Request) -> HTMLResponse:
    """Returns the 401 page of a page that needs a login, with a link to sign in and come back."""
    return _error(
        request,
        None,
        401,
        N_("Please sign in"),
        N_("This page shows personal health data. Please sign in to see it."),
        home=f"{_root(request)}/?next={quote(_here(request), safe='')}",
        link_text=N_("Sign in"),
    )


@router.get(UNSUBSCRIBE_PATH + "{token}", response_class=HTMLResponse)
def unsubscribe_page(token: str, request: Request, db_session: DbSession) -> Response:
    """Shows the page of a reminder e-mail's unsubscribe link (no login): a button that stops the e-mails (a GET
    changes nothing: mail scanners open links), in the patient's language; the 404 page for an unknown link."""
    patient = patient_of_token(db_session=db_session, token=token)
    if patient is None:
        return _unknown_unsubscribe_link(request)
    return _page(request, "unsubscribe.html", None, locale=page_locale(request, patient), done=False,
                 action=_root(request) + UNSUBSCRIBE_PATH + token)  # fmt: skip


@router.post(UNSUBSCRIBE_PATH + "{token}", response_class=HTMLResponse)
def unsubscribe_submit(token: str, request: Request, db_session: DbSession) -> Response:
    """Stops the patient's reminder e-mails (the page's button, or a mail program's one-click POST of RFC 8058)
    and says so; using the link again changes nothing."""
    try:
        patient = unsubscribe(db_session=db_session, token=token)
    except NotFound:
        return _unknown_unsubscribe_link(request)
    return _page(request, "unsubscribe.html", None, locale=page_locale(request, patient), done=True)


def _unknown_unsubscribe_link(request: Request) -> HTMLResponse:
    message = N_("This unsubscribe link belongs to no reminder e-mail. Please check that it is complete.")
    return _error(request, None, 404, N_("Link not found"), message)


@router.get("/static/{name}")
def static_file(name: str) -> Response:
    """Returns one of the pages' static files (css, js)."""
    path = (STATIC / name).resolve()
    if path.parent != STATIC or path.suffix not in _MEDIA or not path.is_file():
        return Response(status_code=404)
    return FileResponse(path, media_type=_MEDIA[path.suffix], headers={"Cache-Control": "no-cache"})
