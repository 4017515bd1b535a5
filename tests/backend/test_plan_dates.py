"""A plan's dates are written as text (YYYY-MM-DD): a number is 422 naming the field, not read as 1970-01-01."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from backend.plans.schemas import PlanIn


@pytest.mark.parametrize("field", ["start_date", "end_date"])
@pytest.mark.parametrize("value", [0, 1_700_000_000, 1.5])
def test_a_number_is_no_date(field, value):
    body = {"title": "p", "start_date": "2026-11-23"} | {field: value}
    with pytest.raises(ValidationError, match=f"{field}[\\s\\S]*written as text"):
        PlanIn.model_validate(body)


def test_a_date_text_is_a_date():
    plan = PlanIn.model_validate({"title": "p", "start_date": "2026-11-23", "end_date": None})
    assert plan.start_date.isoformat() == "2026-11-23"
