"""Request and response bodies of the users, auth and token endpoints."""

from __future__ import annotations

import datetime as dt
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

Role = Literal["admin", "therapist", "patient"]
Scope = Literal["read", "write"]
TOKEN_DEFAULT_DAYS = 90  # an API token's lifetime unless its maker asks for less or more
TOKEN_MAX_DAYS = 365


# an e-mail address as the server takes it: name@domain.tld, no spaces, no second @, no NUL (the schema says so)
EMAIL_PATTERN = r"^[^@\s\x00]+@[^@\s\x00]+\.[^@\s\x00]+$"


class UserOut(BaseModel):
    """A user as the API shows it (never the password hash)."""

    model_config = ConfigDict(from_attributes=True)
    id: int = Field(examples=[7])
    email: str = Field(examples=["ana@example.org"])
    full_name: str = Field(examples=["Ana Silva"])
    role: Role
    is_active: bool
    created_at: dt.datetime


class UserCreate(BaseModel):
    """An admin creates a user."""

    email: str = Field(max_length=320, pattern=EMAIL_PATTERN, examples=["ana@example.org"],
                       description="an e-mail address like ana@example.org; stored in lower case")  # fmt: skip
    full_name: str = Field(default="", max_length=200, examples=["Ana Silva"])
    role: Role = Field(examples=["patient"])
    password: str = Field(min_length=10, max_length=256, examples=["correct horse battery"])

    _lower_email = field_validator("email")(lambda cls, v: v.lower())


class UserUpdate(BaseModel):
    """An admin changes a user's name, active flag or password."""

    full_name: str | None = Field(default=None, max_length=200, examples=["Rose Miller"])
    is_active: bool | None = Field(default=None, examples=[True])
    password: str | None = Field(default=None, min_length=10, max_length=256, examples=["a new long passphrase"])
    keep_api_tokens: bool = Field(
        default=False,
        description="with a new password: keep the user's API tokens (their browser logins end either way)",
    )


class LoginIn(BaseModel):
    """Password login."""

    email: str = Field(max_length=320, examples=["ana@example.org"])
    password: str = Field(max_length=256, examples=["correct horse battery"])


class LoginOut(BaseModel):
    """The logged-in user and the CSRF token to send as X-CSRF-Token on unsafe requests."""

    user: UserOut
    csrf_token: str = Field(examples=["q2Yl1v...Zk"])
    expires_at: dt.datetime


class CsrfOut(BaseModel):
    """The CSRF token of the current login session."""

    csrf_token: str = Field(examples=["0f3c9a1d6b2e4f5a8c7d9e0b1a2c3d4e"])


class TokenCreate(BaseModel):
    """A new personal API token."""

    name: str = Field(min_length=1, max_length=100, examples=["analysis notebook"])
    scopes: list[Scope] = Field(default=["read"], min_length=1, examples=[["read"]])
    expires_in_days: int = Field(
        default=TOKEN_DEFAULT_DAYS,
        ge=1,
        le=TOKEN_MAX_DAYS,
        description=f"lifetime in days ({TOKEN_DEFAULT_DAYS} by default, at most {TOKEN_MAX_DAYS}); a token made "
        "with a token expires no later than the token that made it",
        examples=[30],
    )


class TokenOut(BaseModel):
    """A personal API token (without the secret)."""

    model_config = ConfigDict(from_attributes=True)
    id: int
    name: str
    scopes: list[str]
    created_at: dt.datetime
    last_used_at: dt.datetime | None
    revoked_at: dt.datetime | None
    expires_at: dt.datetime
    parent_id: int | None = Field(description="the token that made this one, if one did; revoking it revokes this")


class TokenCreated(TokenOut):
    """A freshly created token; `token` is shown this once only."""

    token: str = Field(examples=["khc_5bYg...P0"])
