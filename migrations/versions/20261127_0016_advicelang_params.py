"""suggestion.params: what a rule found, so its advice is written in the reader's language when read

Revision ID: advicelang_0016_params
Revises: records_0015_removed_at
Create Date: 2026-11-27 07:40:00

A system suggestion stored before this column has its text only, in the patient's language of that day. Its rule,
metric, threshold and value, its session's day and exercise and the day it was written are enough to write it again
for every rule; such a row gets params only when the text written from them in one of the languages equals its stored
text exactly (so a row is upgraded only when it is recognised for certain); every other row keeps its text and is
shown as it is. Downgrade drops the column: every row still has its text.
"""

import datetime as dt
from collections.abc import Iterator, Sequence
from typing import Any

import sqlalchemy as sa
from alembic import op
from pydantic import ValidationError

from backend.i18n import LOCALES, translator
from backend.suggestions import rules

revision: str = "advicelang_0016_params"
down_revision: str | None = "records_0015_removed_at"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

SUGGESTION = sa.table(
    "suggestion",
    *(sa.column(c) for c in ("id", "session_id", "source", "rule", "metric", "threshold", "value", "text")),
    sa.column("created_at", sa.DateTime),
    sa.column("params", sa.JSON),
)
SESSION = sa.table("exercise_session", sa.column("id"), sa.column("exercise_id"), sa.column("started_at", sa.DateTime))
EXERCISE = sa.table("exercise", sa.column("id"), sa.column("slug"))


def _utc_day(value: dt.datetime | str | None) -> dt.date | None:
    """Returns the UTC day of a stored time (naive UTC on SQLite, sometimes as text; aware on PostgreSQL)."""
    if value is None:
        return None
    if isinstance(value, str):
        value = dt.datetime.fromisoformat(value)
    return (value if value.tzinfo is None else value.astimezone(dt.UTC)).date()


def _whole(value: float | None) -> int | None:
    return int(value) if value is not None and float(value).is_integer() else None


def candidates(rule: str, metric: str, threshold: float | None, value: float | None, exercise: str | None,
               session_on: dt.date | None, written_on: dt.date) -> Iterator[rules.AdviceParams]:  # fmt: skip
    """Yields the params an old suggestion's text may have been written from (one per day it may have been
    written on: the day of created_at, or the day before when the rule ran just before midnight)."""
    if value is None or threshold is None:
        return
    found: dict[str, object] = {}
    if rule == rules.FEWER_REPS:
        found = {"repetitions": value, "goal": _whole(threshold)}
    elif rule == rules.ROM_DROP:
        found = {"rom_deg": value, "baseline_rom_deg": threshold / rules.ROM_DROP_FRACTION}
    elif rule == rules.TOO_FAST:
        found = {"tempo_s_per_rep": value, "advised_s_per_rep": rules.ADVISED_TEMPO_S_PER_REP}
    elif rule == rules.POOR_DATA_QUALITY:
        found = {"tracked_fraction": value} if metric == "quality.tracked_fraction" else {}
    elif rule == rules.MISSED_DAYS:
        found = {"active_days": _whole(value), "expected_days": _whole(threshold), "up_to": session_on}
    elif rule == rules.PAIN_HIGH:
        found = {"pain": _whole(value)}
    elif rule == rules.PAIN_RISING:
        found = {"pain_recent": value, "pain_before": threshold - rules.PAIN_RISE_POINTS}
    else:
        return
    about: dict[str, object] = {"exercise": exercise}
    if rule == rules.PAIN_RISING:
        about = {}
    for day in (written_on, written_on - dt.timedelta(days=1)):
        if rule not in (rules.MISSED_DAYS, rules.PAIN_RISING):
            about = {"exercise": exercise, "session_on": session_on, "written_on": day}
        try:
            yield rules.AdviceParams(**about, **found)
        except ValidationError:
            return


def recognised(row: Any) -> rules.AdviceParams | None:
    """Returns the params from which some language writes exactly the row's stored text, else None."""
    written_on = _utc_day(row.created_at)
    if written_on is None:
        return None
    for params in candidates(row.rule, row.metric, row.threshold, row.value, row.slug, _utc_day(row.started_at),
                             written_on):  # fmt: skip
        for locale in LOCALES:
            try:
                text = rules.advice_text(row.rule, row.metric, params, translator(locale))
            except (ValueError, TypeError, KeyError):
                break
            if text == row.text:
                return params
    return None


def upgrade() -> None:
    op.add_column("suggestion", sa.Column("params", sa.JSON(), nullable=True))
    bind = op.get_bind()
    rows = bind.execute(
        sa.select(SUGGESTION.c.id, SUGGESTION.c.rule, SUGGESTION.c.metric, SUGGESTION.c.threshold,
                  SUGGESTION.c.value, SUGGESTION.c.text, SUGGESTION.c.created_at, SESSION.c.started_at,
                  EXERCISE.c.slug)
        .select_from(SUGGESTION)
        .outerjoin(SESSION, SESSION.c.id == SUGGESTION.c.session_id)
        .outerjoin(EXERCISE, EXERCISE.c.id == SESSION.c.exercise_id)
        .where(SUGGESTION.c.source == "system", SUGGESTION.c.rule.in_(rules.RULES))
        .order_by(SUGGESTION.c.id)
    ).all()  # fmt: skip
    for row in rows:
        params = recognised(row)
        if params is not None:
            bind.execute(sa.update(SUGGESTION).where(SUGGESTION.c.id == row.id)
                         .values(params=params.model_dump(mode="json")))  # fmt: skip


def downgrade() -> None:
    op.drop_column("suggestion", "params")
