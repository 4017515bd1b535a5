"""Users: the caller's own account, and admin management."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Query, status

from backend.audit.service import record
from backend.deps import AdminCaller, CurrentUser, DbSession
from backend.exceptions import (
    AUTH_ERRORS,
    EmailAlreadyRegistered,
    Forbidden,
    UserNotFound,
    error_responses,
)
from backend.schemas import IdPath, Page, PageParams, page_params
from backend.users import service
from backend.users.schemas import Role, UserCreate, UserOut, UserUpdate

router = APIRouter(prefix="/api/v1/users", tags=["users"])


@router.get("/me", response_model=UserOut, responses=error_responses(*AUTH_ERRORS))
def me(user: CurrentUser) -> UserOut:
    """Returns the calling user."""
    return UserOut.model_validate(user)


@router.get("", response_model=Page[UserOut], responses=error_responses(*AUTH_ERRORS))
def list_users(
    caller: AdminCaller,
    db_session: DbSession,
    page: Annotated[PageParams, Depends(page_params)],
    role: Annotated[Role | None, Query()] = None,
) -> Page[UserOut]:
    """Lists users (admin only), optionally of one role."""
    rows, total = service.list_users(db_session=db_session, limit=page.limit, offset=page.offset, role=role)
    return Page[UserOut](
        items=[UserOut.model_validate(u) for u in rows], total=total, limit=page.limit, offset=page.offset
    )


@router.post(
    "",
    response_model=UserOut,
    status_code=status.HTTP_201_CREATED,
    responses=error_responses(*AUTH_ERRORS, EmailAlreadyRegistered),
)
def create_user(body: UserCreate, caller: AdminCaller, db_session: DbSession) -> UserOut:
    """Creates a user (admin only)."""
    user = service.create_user(
        db_session=db_session, email=body.email, password=body.password, role=body.role, full_name=body.full_name
    )
    record(
        db_session=db_session,
        caller=caller,
        action="user.create",
        object_type="user",
        object_id=user.id,
        patient_id=user.id if user.role == "patient" else None,
    )
    return UserOut.model_validate(user)


@router.get("/{user_id}", response_model=UserOut, responses=error_responses(*AUTH_ERRORS, UserNotFound))
def get_user(user_id: IdPath, caller: AdminCaller, db_session: DbSession) -> UserOut:
    """Returns one user (admin only)."""
    user = service.get_user(db_session=db_session, user_id=user_id)
    record(
        db_session=db_session,
        caller=caller,
        action="user.read",
        object_type="user",
        object_id=user.id,
        patient_id=user.id if user.role == "patient" else None,
    )
    return UserOut.model_validate(user)


@router.patch("/{user_id}", response_model=UserOut, responses=error_responses(*AUTH_ERRORS, UserNotFound))
def update_user(user_id: IdPath, body: UserUpdate, caller: AdminCaller, db_session: DbSession) -> UserOut:
    """Changes a user's name, password or active flag (admin only). A new password ends the user's browser logins
    (except the caller's own, when admins change their own password) and API tokens unless keep_api_tokens;
    deactivation revokes all of them."""
    user = service.get_user(db_session=db_session, user_id=user_id)
    if body.is_active is False and user.id == caller.signed_in_user.id:
        raise Forbidden("admins cannot deactivate themselves")
    service.update_user(
        db_session=db_session,
        user=user,
        full_name=body.full_name,
        is_active=body.is_active,
        password=body.password,
        keep_api_tokens=body.keep_api_tokens,
        keep_login=caller.login_session,
    )
    record(
        db_session=db_session,
        caller=caller,
        action="user.update",
        object_type="user",
        object_id=user.id,
        patient_id=user.id if user.role == "patient" else None,
        detail={"fields": sorted(body.model_dump(exclude_unset=True, exclude={"password"}))},
    )
    return UserOut.model_validate(user)
