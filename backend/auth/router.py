"""Browser login/logout/CSRF and personal API tokens."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Request, Response, status

from backend.audit.service import record
from backend.config import Settings, get_settings
from backend.deps import SESSION_COOKIE, Caller, CurrentUser, DbSession, UserCaller, client_ip, current_caller
from backend.exceptions import (
    AUTH_ERRORS,
    Forbidden,
    InsufficientScope,
    NotAuthenticated,
    TokenNotFound,
    TooManyLoginAttempts,
    error_responses,
)
from backend.schemas import IdPath, Page, PageParams, page_params
from backend.users import service
from backend.users.schemas import CsrfOut, LoginIn, LoginOut, TokenCreate, TokenCreated, TokenOut, UserOut

router = APIRouter(prefix="/api/v1", tags=["auth"])


@router.post(
    "/auth/login",
    response_model=LoginOut,
    responses=error_responses(NotAuthenticated, TooManyLoginAttempts),
    summary="Log in with e-mail and password (sets the session cookie)",
)
def login(
    body: LoginIn,
    request: Request,
    response: Response,
    db_session: DbSession,
    settings: Annotated[Settings, Depends(get_settings)],
) -> LoginOut:
    """Checks the password, sets the HttpOnly SameSite=Lax session cookie and returns the CSRF token."""
    user, login_session, token = service.login(
        db_session=db_session, settings=settings, email=body.email, password=body.password, ip=client_ip(request)
    )
    max_age = int(settings.LOGIN_SESSION_HOURS * 3600)
    response.set_cookie(
        SESSION_COOKIE,
        token,
        max_age=max_age,
        httponly=True,
        secure=settings.cookie_secure,
        samesite="lax",
        path="/",
    )
    return LoginOut(
        user=UserOut.model_validate(user), csrf_token=login_session.csrf_secret, expires_at=login_session.expires_at
    )


@router.post(
    "/auth/logout",
    status_code=status.HTTP_204_NO_CONTENT,
    responses=error_responses(*AUTH_ERRORS),
    summary="End the browser login session",
)
def logout(caller: Annotated[Caller, Depends(current_caller)], response: Response, db_session: DbSession) -> None:
    """Revokes the login session of the cookie and clears the cookie (API tokens are revoked via /tokens)."""
    if caller.login_session is not None:
        service.logout(db_session=db_session, login_session=caller.login_session)
    response.delete_cookie(SESSION_COOKIE, path="/")


@router.get("/auth/csrf", response_model=CsrfOut, responses=error_responses(NotAuthenticated, Forbidden))
def csrf(caller: UserCaller) -> CsrfOut:
    """Returns the CSRF token of the cookie session, to send as X-CSRF-Token on unsafe requests."""
    if caller.login_session is None:
        raise Forbidden("CSRF tokens exist only for cookie logins; bearer tokens need none")
    return CsrfOut(csrf_token=caller.login_session.csrf_secret)


@router.post(
    "/tokens",
    response_model=TokenCreated,
    status_code=status.HTTP_201_CREATED,
    responses=error_responses(*AUTH_ERRORS),
    tags=["tokens"],
)
def create_token(body: TokenCreate, user: CurrentUser, caller: UserCaller, db_session: DbSession) -> TokenCreated:
    """Creates a personal API token; the secret is in the answer only this once."""
    if caller.via == "token" and not set(body.scopes) <= caller.scopes:
        raise InsufficientScope("an API token cannot create a token with more scopes than its own")
    row, token = service.create_api_token(
        db_session=db_session,
        user=user,
        name=body.name,
        scopes=body.scopes,
        days=body.expires_in_days,
        parent=caller.api_token,
    )
    record(db_session=db_session, caller=caller, action="token.create", object_type="api_token", object_id=row.id)
    return TokenCreated(**TokenOut.model_validate(row).model_dump(), token=token)


@router.get("/tokens", response_model=Page[TokenOut], responses=error_responses(*AUTH_ERRORS), tags=["tokens"])
def list_tokens(
    user: CurrentUser, db_session: DbSession, page: Annotated[PageParams, Depends(page_params)]
) -> Page[TokenOut]:
    """Lists the caller's API tokens, newest first."""
    rows, total = service.list_api_tokens(db_session=db_session, user=user, limit=page.limit, offset=page.offset)
    return Page[TokenOut](
        items=[TokenOut.model_validate(r) for r in rows], total=total, limit=page.limit, offset=page.offset
    )


@router.delete(
    "/tokens/{token_id}",
    status_code=status.HTTP_204_NO_CONTENT,
    responses=error_responses(*AUTH_ERRORS, TokenNotFound),
    tags=["tokens"],
)
def revoke_token(token_id: IdPath, user: CurrentUser, caller: UserCaller, db_session: DbSession) -> None:
    """Revokes one of the caller's API tokens."""
    service.revoke_api_token(db_session=db_session, user=user, token_id=token_id)
    record(db_session=db_session, caller=caller, action="token.revoke", object_type="api_token", object_id=token_id)
