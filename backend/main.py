"""The FastAPI application: routers, error handlers, health and version endpoints, start-up migration check."""

from __future__ import annotations

import asyncio
import importlib
import logging
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from importlib.metadata import entry_points

from fastapi import APIRouter, Depends, FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from pydantic import BaseModel, Field
from sqlalchemy import text
from sqlalchemy.engine import Engine
from sqlalchemy.exc import DBAPIError
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.middleware.gzip import GZipMiddleware

from backend import __version__
from backend.allowed_methods import allowed_methods, refuse_undocumented_method
from backend.api_docs import mount as mount_api_docs
from backend.config import Settings, get_settings
from backend.database import get_engine, is_database_busy
from backend.db_slots import DbAdmission, DbSlots
from backend.deps import DbSession
from backend.events.listener import Listener
from backend.exceptions import AppError, DatabaseBusy
from backend.i18n.errors import error_detail
from backend.live.progress_gate import ProgressGate
from backend.openapi import openapi_builder
from backend.request_limits import RequestLimits
from backend.schemas import ErrorOut
from backend.security_headers import SecurityHeaders
from kinect_agent.blas_threads import one_blas_thread
from kinect_agent.processing.errors import ProcessingError

log = logging.getLogger(__name__)

ROUTERS = (
    "backend.auth.router",
    "backend.users.router",
    "backend.patients.router",
    "backend.devices.router",
    "backend.exercises.router",
    "backend.plans.router",
    "backend.audit.router",
    "backend.session_review.router",  # before sessions: POST /sessions stays first of its path, as it was
    "backend.sessions.router",
    "backend.suggestions.router",
    "backend.replay.router",
    "backend.events.router",
    "backend.live.router",
    "backend.camera.router",
    "backend.records.router",
    "backend.records.reanalysis_router",
    "backend.voice.router",
    "backend.exercises.demo_router",
    "backend.feeling.router",
    "backend.replies.router",
    "backend.reminders.router",
)
# Packages above the server (the pages, frontend.pages:mount) register a mount function in this entry-point group
# (pyproject.toml); the server calls each on the app it builds and never imports them (docs/architecture.md).
MOUNTS_GROUP = "kinect_home_coach.server_mounts"


def registered_mounts() -> list[Callable[[FastAPI], None]]:
    """Returns the mount functions installed in MOUNTS_GROUP, sorted by name."""
    return [ep.load() for ep in sorted(entry_points(group=MOUNTS_GROUP), key=lambda ep: ep.name)]


class HealthOut(BaseModel):
    """Liveness and database reachability."""

    status: str = Field(examples=["ok"])
    database: str = Field(examples=["ok"])


class VersionOut(BaseModel):
    """Server and API version."""

    version: str = Field(examples=[__version__])
    api: str = Field(examples=["v1"])
    database_revision: str = Field(examples=["0001"])


MAX_LISTED_ERRORS = 10  # a 1 MiB body of 90 000 unknown keys would otherwise be answered with 4 MB of detail


def _validation_detail(exc: RequestValidationError) -> str:
    """Returns the first MAX_LISTED_ERRORS problems of a request, each naming its field, and how many more there are."""
    errors = exc.errors()
    parts = []
    for err in errors[:MAX_LISTED_ERRORS]:
        where = ".".join(str(p) for p in err.get("loc", ()))
        parts.append(f"{where}: {err.get('msg', 'invalid')}")
    if len(errors) > MAX_LISTED_ERRORS:
        parts.append(f"and {len(errors) - MAX_LISTED_ERRORS} more")
    return "; ".join(parts) or "invalid request"


def _page_for(app: FastAPI, request: Request, status_code: int) -> Response | None:
    """Returns the HTML error page the mounted pages give a browser (app.state.error_page), or None: JSON."""
    render = getattr(app.state, "error_page", None)
    return render(request, status_code) if render is not None else None


def _install_error_handlers(app: FastAPI) -> None:
    @app.exception_handler(AppError)
    async def app_error(request: Request, exc: AppError) -> JSONResponse:
        detail, language = error_detail(request, exc.message)
        return JSONResponse(
            {"error": type(exc).__name__, "detail": detail}, status_code=exc.status_code,
            headers=(exc.headers or {}) | language,
        )  # fmt: skip

    @app.exception_handler(ProcessingError)
    async def processing_fault(request: Request, exc: ProcessingError) -> JSONResponse:
        # an internal fault on input the server accepted: logged with the request and the notes the layers added
        log.error("internal fault of the signal processing in %s %s", request.method, request.url.path, exc_info=exc)
        detail = f"internal fault of the signal processing ({exc}); the request was valid, the fault is the server's"
        return JSONResponse({"error": type(exc).__name__, "detail": detail}, status_code=500)

    @app.exception_handler(RequestValidationError)
    async def validation_error(request: Request, exc: RequestValidationError) -> Response:
        page = _page_for(app, request, 404) if request.method == "GET" else None
        if page is not None:  # a page address with a malformed id: no such page
            return page
        return JSONResponse({"error": "ValidationError", "detail": _validation_detail(exc)}, status_code=422)

    @app.exception_handler(StarletteHTTPException)
    async def http_error(request: Request, exc: StarletteHTTPException) -> Response:
        allowed = allowed_methods(app, request) if exc.status_code == 405 else []
        if allowed and request.method == "OPTIONS":
            return Response(status_code=204, headers={"Allow": ", ".join(allowed)})
        if allowed:
            exc.headers = {**(exc.headers or {}), "Allow": ", ".join(allowed)}
        page = _page_for(app, request, exc.status_code)
        if page is not None:
            page.headers.update(exc.headers or {})
            return page
        name = {404: "NotFound", 405: "MethodNotAllowed"}.get(exc.status_code, "HTTPError")
        return JSONResponse(
            {"error": name, "detail": str(exc.detail)}, status_code=exc.status_code, headers=exc.headers
        )

    @app.exception_handler(DBAPIError)
    async def database_error(request: Request, exc: DBAPIError) -> JSONResponse:
        if is_database_busy(exc):
            busy = DatabaseBusy("the database is busy with another write; retry in a second")
            return await app_error(request, busy)
        return await unexpected(request, exc)

    @app.exception_handler(Exception)
    async def unexpected(_request: Request, exc: Exception) -> JSONResponse:
        log.exception("unhandled error", exc_info=exc)
        return JSONResponse({"error": "InternalError", "detail": "internal server error"}, status_code=500)


def _system_router() -> APIRouter:
    router = APIRouter(tags=["system"])

    @router.get("/healthz", response_model=HealthOut, responses={503: {"model": ErrorOut}})
    def healthz(db_session: DbSession) -> HealthOut | JSONResponse:
        """Answers 200 when the server runs and the database answers, 503 otherwise."""
        try:
            db_session.execute(text("SELECT 1"))
        except Exception as exc:  # noqa: BLE001 - any database failure means unhealthy
            log.warning("health check failed: %s", exc)
            return JSONResponse({"error": "DatabaseUnavailable", "detail": "database unreachable"}, status_code=503)
        return HealthOut(status="ok", database="ok")

    @router.get("/api/v1/version", response_model=VersionOut)
    def version() -> VersionOut:
        """Returns the server version, API version and the schema revision the code expects."""
        from backend.migrate import head_revision

        return VersionOut(version=__version__, api="v1", database_revision=head_revision())

    return router


class _Reminders:
    """The reminder e-mail loop of this server process (backend.reminders.sender), stopped with the app."""

    def __init__(self, settings: Settings, engine: Engine):
        from sqlalchemy.orm import sessionmaker

        from backend.reminders.sender import run

        self.stopping = asyncio.Event()
        factory = sessionmaker(bind=engine, expire_on_commit=False)
        self.task = asyncio.create_task(run(sessions=factory, settings=settings, stop=self.stopping))

    async def stop(self) -> None:
        """Ends the loop (after the check in hand)."""
        self.stopping.set()
        await self.task


def _start_reminders(settings: Settings, engine: Engine) -> _Reminders | None:
    """Starts the reminder e-mail loop when an SMTP server is configured (COACH_SMTP_HOST), else returns None."""
    return _Reminders(settings, engine) if settings.reminder_emails else None


def create_app(settings: Settings | None = None, engine: Engine | None = None) -> FastAPI:
    """Returns the configured application; at start-up it refuses a database that is not at Alembic head. Every
    worker runs BLAS on one thread (kinect_agent.blas_threads: the analysis' matrices are small)."""
    settings = settings or get_settings()
    one_blas_thread()

    @asynccontextmanager
    async def lifespan(_app: FastAPI) -> AsyncIterator[None]:
        bound = engine or get_engine()
        if settings.CHECK_MIGRATIONS:
            from backend.migrate import check_at_head

            check_at_head(bound)
        if settings.LIVE_WARM_UP:  # the camera sets' live filter compiles (or loads) now, not at a patient's first set
            from backend.camera.live_count import start_warm_up

            start_warm_up()
        # PostgreSQL carries the pages' events between workers and replicas (backend/events); SQLite: in-process
        listener = Listener(bound.url).start() if bound.dialect.name == "postgresql" else None
        reminders = _start_reminders(settings, bound)
        worker = None
        if settings.EMBEDDED_WORKER:  # replay builds and re-analysis without a separate `coach-server worker`
            from sqlalchemy.orm import sessionmaker

            from backend.jobs.worker import EmbeddedWorker

            worker = EmbeddedWorker(sessionmaker=sessionmaker(bind=bound, expire_on_commit=False),
                                    settings=settings).start()  # fmt: skip
        try:
            yield
        finally:
            if worker is not None:
                worker.stop()
            if reminders is not None:
                await reminders.stop()
            if listener is not None:
                listener.stop()

    app = FastAPI(
        title="Kinect Home Coach",
        version=__version__,
        description="Coaching server: accounts, patients, devices, exercise plans, sessions and suggestions.",
        lifespan=lifespan,
        docs_url=None,  # backend.api_docs serves /docs from the app itself; no /redoc (api_docs says why)
        redoc_url=None,
        dependencies=[Depends(refuse_undocumented_method)],  # 405 before any other check (backend.allowed_methods)
    )
    app.state.settings = settings
    app.state.live_progress = ProgressGate()  # live progress: per-device rate limit and deduplication
    _install_error_handlers(app)
    # plotly.js (1.5 MB), viser's client and JSON compress 3-5x; the replay recording is already zstd (identity)
    app.add_middleware(GZipMiddleware, minimum_size=1024)
    # a request waits for a database slot in the event loop, not in a thread holding a connection (backend/db_slots)
    app.state.db_slots = DbSlots(lambda: engine or get_engine(), wait_s=settings.DB_SLOT_WAIT_S)
    app.add_middleware(DbAdmission, slots=app.state.db_slots)
    app.add_middleware(RequestLimits, max_json_bytes=settings.MAX_JSON_BYTES)  # before anything reads the body
    app.add_middleware(SecurityHeaders, hsts=settings.hsts)  # outermost: on every answer, errors too
    # no redirect from /path/ to /path: Starlette builds its absolute Location from the request's Host header
    app.router.redirect_slashes = False
    app.include_router(_system_router())
    for name in ROUTERS:
        app.include_router(importlib.import_module(name).router)
    for mount in registered_mounts():  # the HTML pages and their error pages, not in the OpenAPI schema
        mount(app)
    mount_api_docs(app)
    app.openapi = openapi_builder(app)  # type: ignore[method-assign]
    return app
