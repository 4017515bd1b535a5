"""Schemas shared by every domain: the error body and the paginated list envelope."""

from __future__ import annotations

from typing import Annotated, Generic, TypeVar

from fastapi import Path, Query
from pydantic import BaseModel, ConfigDict, Field

T = TypeVar("T")


class ErrorOut(BaseModel):
    """The body of every error response."""

    error: str = Field(examples=["PatientNotFound"])
    detail: str = Field(examples=["patient 12 does not exist"])


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
