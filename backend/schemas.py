"""Schemas shared by every domain: the error body and the paginated list envelope."""

from __future__ import annotations

import datetime as dt
import re
from dataclasses import dataclass
from typing import Annotated, Generic, TypeVar

from fastapi import Path, Query
from pydantic import AwareDatetime, BaseModel, BeforeValidator, ConfigDict, Field, JsonValue

T = TypeVar("T")


class ErrorOut(BaseModel):
    """The body of every error response."""

    error: str = Field(examples=["PatientNotFound"])
    detail: str = Field(examples=["patient 12 does not exist"])


@dataclass(frozen=True)
class BodyRule:
    """A rule of a request body that JSON Schema cannot state (it relates two fields): its name, the rule in words,
    and what its validator raises. A body model lists its rules in `body_rules`; the OpenAPI document names each in
    the model's schema ("x-body-rules") and as an example of the 422 answer of every operation that takes the body
    (backend.openapi)."""

    name: str
    rule: str
    message: str

    @property
    def detail(self) -> str:
        """Returns the detail of the 422 ValidationError that refuses a body breaking the rule."""
        return f"body: Value error, {self.message}"

    def as_schema(self) -> dict[str, JsonValue]:
        """Returns the rule as the model's JSON schema lists it."""
        return {"name": self.name, "rule": self.rule, "detail": self.detail}


class Page(BaseModel, Generic[T]):
    """One page of a list: items, the total number of matches, and the limit/offset used."""

    items: list[T]
    total: int = Field(ge=0, examples=[42])
    limit: int = Field(examples=[50])
    offset: int = Field(examples=[0])


class PageParams(BaseModel):
    """Pagination query parameters."""

    model_config = ConfigDict(frozen=True)
    limit: int = 50
    offset: int = 0


def page_params(
    limit: Annotated[int, Query(ge=1, le=200, description="page size")] = 50,
    offset: Annotated[int, Query(ge=0, le=10_000_000, description="items to skip")] = 0,
) -> PageParams:
    """Returns the validated pagination parameters of a list request."""
    return PageParams(limit=limit, offset=offset)


MAX_ID = 2**31 - 1
IdPath = Annotated[int, Path(ge=1, le=MAX_ID)]
IdQuery = Annotated[int | None, Query(ge=1, le=MAX_ID)]

# RFC 3339 date-time, as OpenAPI's "date-time" format says: date, time and offset ("Z" or +hh:mm)
_RFC3339 = re.compile(r"\d{4}-\d{2}-\d{2}[Tt ]\d{2}:\d{2}:\d{2}(\.\d+)?([Zz]|[+-]\d{2}:\d{2})")


def _rfc3339(value: object) -> object:
    """Passes on an RFC 3339 date-time text; refuses numbers, bare dates and times without an offset, which
    pydantic's lax parsing would otherwise read."""
    if isinstance(value, dt.datetime):
        return value
    if not isinstance(value, str) or not _RFC3339.fullmatch(value):
        raise ValueError("must be a date-time with its offset, e.g. 2026-11-01T09:30:00Z")
    return value


DateTimeQuery = Annotated[AwareDatetime | None, BeforeValidator(_rfc3339)]
