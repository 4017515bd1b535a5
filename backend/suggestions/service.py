"""Suggestion queries and changes: store rule drafts, list what a caller may see, write, approve and dismiss."""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterable
from typing import Any, cast

from pydantic import ValidationError
from sqlalchemy import ColumnElement, and_, func, or_, select, update
from sqlalchemy.engine import CursorResult
from sqlalchemy.orm import Session

from backend.database import utcnow
from backend.exceptions import SuggestionNotFound, SuggestionNotPending
from backend.exercises.models import Exercise
from backend.feeling.models import SessionFeeling
from backend.i18n import DEFAULT_LOCALE, Translator, asked_locale, translator
from backend.sessions.history import plan_targets, session_history
from backend.sessions.models import ExerciseSession
from backend.suggestions.models import Suggestion
from backend.suggestions.rules import (
    ACTIVE_DAYS_WINDOW,
    MISSED_DAYS,
    PAIN_BASELINE_DAYS,
    PAIN_HIGH,
    PAIN_RECENT_DAYS,
    PAIN_RISING,
    RULES,
    AdviceParams,
    SessionDay,
    SuggestionDraft,
    advice_text,
    evaluate,
    pain_high,
    pain_rising,
)
from backend.suggestions.schemas import SuggestionOut
from backend.users.models import User
from kinect_agent.analysis.document import AnalysisReport

THERAPIST_RULE = "therapist"  # the rule field of suggestions written by a person


def missing(suggestion_id: int) -> SuggestionNotFound:
    """Returns the error for a suggestion that does not exist, or that the caller has no right to know of."""
    return SuggestionNotFound(f"suggestion {suggestion_id} does not exist")


def add_system_suggestions(
    drafts: Iterable[SuggestionDraft], *, patient_id: int, session_id: int | None, db_session: Session
) -> list[Suggestion]:
    """Stores drafts as pending system suggestions of a patient's session and returns them (flushed, not committed).

    A draft whose rule already has a suggestion for the same session is skipped, so re-processing a session does
    not repeat advice.
    """
    existing: set[str] = set()
    if session_id is not None:
        existing = set(
            db_session.scalars(
                select(Suggestion.rule).where(Suggestion.session_id == session_id, Suggestion.source == "system")
            )
        )
    now = utcnow()
    rows = []
    for i, draft in enumerate(drafts):
        if not isinstance(draft, SuggestionDraft) or draft.rule not in RULES:
            raise ValueError(f"drafts[{i}] must be a SuggestionDraft of a known rule {RULES}, got {draft!r:.120}")
        if draft.rule in existing:
            continue
        existing.add(draft.rule)
        rows.append(
            Suggestion(
                patient_id=patient_id,
                session_id=session_id,
                source="system",
                rule=draft.rule,
                metric=draft.metric,
                comparison=draft.comparison,
                threshold=float(draft.threshold),
                value=float(draft.value),
                text=draft.text,
                params=draft.params.model_dump(mode="json"),
                status="pending",
                created_at=now,
            )
        )
    db_session.add_all(rows)
    db_session.flush()
    return rows


def add_therapist_suggestion(
    *, db_session: Session, patient_id: int, author_id: int, text: str, session_id: int | None
) -> Suggestion:
    """Stores a suggestion written by a therapist or admin; it needs no approval."""
    now = utcnow()
    row = Suggestion(
        patient_id=patient_id,
        session_id=session_id,
        author_id=author_id,
        source="therapist",
        rule=THERAPIST_RULE,
        metric="",
        comparison="",
        threshold=None,
        text=text,
        status="approved",
        created_at=now,
        decided_at=now,
        decided_by_id=author_id,
    )
    db_session.add(row)
    db_session.flush()
    return row


def visible_to_patient() -> ColumnElement[bool]:
    """Returns the filter of what a patient (or their device) sees: therapist-written and approved system ones."""
    return or_(Suggestion.source == "therapist", and_(Suggestion.source == "system", Suggestion.status == "approved"))


def is_visible_to_patient(suggestion: Suggestion) -> bool:
    """Returns whether a patient (or their device) may see the suggestion; same rule as visible_to_patient()."""
    return suggestion.source == "therapist" or suggestion.status == "approved"


def list_suggestions(
    *,
    db_session: Session,
    patient_id: int,
    patient_view: bool,
    status: str | None,
    session_id: int | None,
    limit: int,
    offset: int,
    decided: bool | None = None,
) -> tuple[list[Suggestion], int]:
    """Returns one page of a patient's suggestions (newest first) and the total; patient_view hides undecided ones."""
    query = select(Suggestion).where(Suggestion.patient_id == patient_id)
    if patient_view:
        query = query.where(visible_to_patient())
    if status is not None:
        query = query.where(Suggestion.status == status)
    if session_id is not None:
        query = query.where(Suggestion.session_id == session_id)
    if decided is not None:
        query = query.where((Suggestion.status != "pending") if decided else (Suggestion.status == "pending"))
    total = db_session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = db_session.scalars(
        query.order_by(Suggestion.created_at.desc(), Suggestion.id.desc()).limit(limit).offset(offset)
    )
    return list(rows), total


def session_dates(*, db_session: Session, session_ids: set[int]) -> dict[int, dt.datetime]:
    """Returns when each of these sessions started (the sessions advice is about)."""
    if not session_ids:
        return {}
    rows = db_session.execute(
        select(ExerciseSession.id, ExerciseSession.started_at).where(ExerciseSession.id.in_(session_ids))
    )
    return {sid: started for sid, started in rows}


def suggestion_outs(rows: Iterable[Suggestion], *, db_session: Session, accept_language: str | None
                    ) -> list[SuggestionOut]:  # fmt: skip
    """Returns suggestions as the API shows them: each with the start of the session it is about, its text in the
    reader's language (reader()) when it was written by a rule."""
    rows = list(rows)
    started = session_dates(db_session=db_session, session_ids={r.session_id for r in rows if r.session_id})
    readers: dict[int, Translator] = {}
    out = []
    for r in rows:
        if r.patient_id not in readers:
            readers[r.patient_id] = reader(accept_language, db_session=db_session, patient_id=r.patient_id)
        text, locale = shown_text(r, readers[r.patient_id])
        when = started.get(r.session_id) if r.session_id is not None else None
        shown = {"session_started_at": when, "text": text, "locale": locale}
        out.append(SuggestionOut.model_validate(r).model_copy(update=shown))
    return out


def get_suggestion(*, db_session: Session, suggestion_id: int) -> Suggestion:
    """Returns one suggestion or raises SuggestionNotFound."""
    row = db_session.get(Suggestion, suggestion_id)
    if row is None:
        raise missing(suggestion_id)
    return row


def decide(*, db_session: Session, suggestion: Suggestion, status: str, decided_by_id: int) -> Suggestion:
    """Approves or dismisses a pending system suggestion; raises SuggestionNotPending for any other."""
    if status not in ("approved", "dismissed"):
        raise ValueError(f"status must be 'approved' or 'dismissed', got {status!r}")
    if suggestion.source != "system":
        raise SuggestionNotPending(
            f"suggestion {suggestion.id} was written by a therapist; only pending system suggestions can be decided"
        )
    if suggestion.status != "pending":
        raise SuggestionNotPending(
            f"suggestion {suggestion.id} is already {suggestion.status}; only pending suggestions can be decided"
        )
    # conditional UPDATE: of two concurrent decisions exactly one wins, the other gets SuggestionNotPending
    result = db_session.execute(
        update(Suggestion)
        .where(Suggestion.id == suggestion.id, Suggestion.status == "pending")
        .values(status=status, decided_at=utcnow(), decided_by_id=decided_by_id)
        .execution_options(synchronize_session="fetch")
    )
    db_session.refresh(suggestion)
    if cast("CursorResult[Any]", result).rowcount != 1:  # an UPDATE's result is a CursorResult
        raise SuggestionNotPending(
            f"suggestion {suggestion.id} is already {suggestion.status}; only pending suggestions can be decided"
        )
    return suggestion


def _recently_suggested(*, db_session: Session, session: ExerciseSession, rule: str, days: int) -> bool:
    """Returns whether a system suggestion of this rule exists for a session of the same exercise in the last days."""
    since = session.started_at - dt.timedelta(days=days)
    found = db_session.scalar(
        select(Suggestion.id)
        .join(ExerciseSession, ExerciseSession.id == Suggestion.session_id)
        .where(
            Suggestion.patient_id == session.patient_id,
            Suggestion.source == "system",
            Suggestion.rule == rule,
            ExerciseSession.exercise_id == session.exercise_id,
            ExerciseSession.id != session.id,
            ExerciseSession.started_at > since,
            ExerciseSession.started_at <= session.started_at,
        )
        .limit(1)
    )
    return found is not None


def patient_locale(*, db_session: Session, patient_id: int) -> str | None:
    """Returns the language a patient reads their advice in (None: not chosen, English)."""
    return db_session.scalar(select(User.locale).where(User.id == patient_id))


def reader(accept_language: str | None, *, db_session: Session, patient_id: int) -> Translator:
    """Returns the language a patient's advice is shown in to a request: the one its Accept-Language asks for when
    that names a supported locale (the pages send theirs), else the patient's chosen language, else English."""
    asked = asked_locale(accept_language)
    if asked is not None:
        return translator(asked)
    return translator(patient_locale(db_session=db_session, patient_id=patient_id) or DEFAULT_LOCALE)


def shown_text(row: Suggestion, t: Translator) -> tuple[str, str | None]:
    """Returns a suggestion's text as a reader of t's language sees it, and its language: a system suggestion
    written from what its rule found (params), in t's; otherwise (a therapist's, or one stored before params) its
    text as written, language None (not known)."""
    if row.source != "system" or row.params is None:
        return row.text, None
    try:
        return advice_text(row.rule, row.metric, AdviceParams.model_validate(row.params), t), t.locale
    except (ValidationError, ValueError):
        return row.text, None


def suggest_for_session(*, db_session: Session, session: ExerciseSession, doc: AnalysisReport) -> list[Suggestion]:
    """Runs the rules on a stored session's metrics document and stores what fires as pending suggestions.

    Reads the plan's targets and the patient's earlier sessions; judges missed days at most once a week per
    exercise. Keeps at most one pending suggestion per rule and exercise: the newest session's. Returns the new
    suggestions (flushed, not committed).
    """
    reps, per_week = plan_targets(
        db_session=db_session,
        patient_id=session.patient_id,
        exercise_id=session.exercise_id,
        on=session.started_at.astimezone(dt.UTC).date(),
    )
    history = session_history(db_session=db_session, session=session)
    drafts = evaluate(
        doc,
        prescribed_reps=reps,
        history=history,
        expected_per_week=per_week,
        now=session.started_at,
        today=utcnow().date(),
        t=translator(patient_locale(db_session=db_session, patient_id=session.patient_id)),
    )
    if any(d.rule == MISSED_DAYS for d in drafts) and _recently_suggested(
        db_session=db_session, session=session, rule=MISSED_DAYS, days=ACTIVE_DAYS_WINDOW
    ):
        drafts = [d for d in drafts if d.rule != MISSED_DAYS]
    rows = add_system_suggestions(drafts, patient_id=session.patient_id, session_id=session.id, db_session=db_session)
    supersede_older(db_session=db_session, session=session, rules={r.rule for r in rows})
    newer = _pending_from_newer_sessions(db_session=db_session, session=session, rules={r.rule for r in rows})
    for row in rows:
        if row.rule in newer:  # a session uploaded late: its advice is born replaced by the newer one
            row.status, row.decided_at = "superseded", row.created_at
    db_session.flush()
    return rows


def _pending_from_newer_sessions(*, db_session: Session, session: ExerciseSession, rules: set[str]) -> set[str]:
    """Returns which of these rules have a pending system suggestion of a later session of the same exercise."""
    if not rules:
        return set()
    later = select(ExerciseSession.id).where(
        ExerciseSession.patient_id == session.patient_id,
        ExerciseSession.exercise_id == session.exercise_id,
        ExerciseSession.started_at > session.started_at,
    )
    found = db_session.scalars(
        select(Suggestion.rule).where(
            Suggestion.patient_id == session.patient_id,
            Suggestion.source == "system",
            Suggestion.status == "pending",
            Suggestion.rule.in_(sorted(rules)),
            Suggestion.session_id.in_(later),
        )
    )
    return set(found)


def supersede_older(*, db_session: Session, session: ExerciseSession, rules: set[str]) -> int:
    """Marks 'superseded' the patient's pending system suggestions of these rules from earlier sessions of the same
    exercise (a session uploaded late never replaces newer advice); returns how many changed."""
    if not rules:
        return 0
    earlier = select(ExerciseSession.id).where(
        ExerciseSession.patient_id == session.patient_id,
        ExerciseSession.exercise_id == session.exercise_id,
        ExerciseSession.started_at < session.started_at,
    )
    result = db_session.execute(
        update(Suggestion)
        .where(
            Suggestion.patient_id == session.patient_id,
            Suggestion.source == "system",
            Suggestion.status == "pending",
            Suggestion.rule.in_(sorted(rules)),
            Suggestion.session_id.in_(earlier),
        )
        .values(status="superseded", decided_at=utcnow())
        .execution_options(synchronize_session="fetch")
    )
    return cast("CursorResult[Any]", result).rowcount


def suggest_for_feeling(
    *, db_session: Session, session: ExerciseSession, pain: int | None, alert_above: int
) -> list[Suggestion]:
    """Runs the pain rules when the patient says how a set felt: pain above their alert level (0-9), and the median
    pain of the week up to the set rising over the 4 weeks before. Stores what fires as pending suggestions of the
    session (once per rule and session; the therapist reviews them before the patient sees them) and supersedes
    older pending ones of the same rules; a changed answer withdraws (supersedes) the session's pending pain advice
    that no longer holds. Returns the new suggestions (flushed, not committed)."""
    if pain is None:
        _withdraw(db_session=db_session, session=session, rules={PAIN_HIGH, PAIN_RISING})
        return []
    started = session.started_at if session.started_at.tzinfo else session.started_at.replace(tzinfo=dt.UTC)
    since = started - dt.timedelta(days=PAIN_RECENT_DAYS + PAIN_BASELINE_DAYS)
    rows = db_session.execute(
        select(ExerciseSession.started_at, SessionFeeling.pain_nrs)
        .join(SessionFeeling, SessionFeeling.session_id == ExerciseSession.id)
        .where(
            ExerciseSession.patient_id == session.patient_id,
            ExerciseSession.started_at >= since,
            ExerciseSession.started_at <= session.started_at,
            SessionFeeling.pain_nrs.is_not(None),
        )
    ).all()
    answers = [(t if t.tzinfo else t.replace(tzinfo=dt.UTC), p) for t, p in rows if p is not None]
    t = translator(patient_locale(db_session=db_session, patient_id=session.patient_id))
    slug = db_session.scalar(select(Exercise.slug).where(Exercise.id == session.exercise_id))
    day = SessionDay.of(started, utcnow().date())
    drafts = [pain_high(pain, alert_above, slug, day, t), pain_rising(answers, started, t)]
    _withdraw(db_session=db_session, session=session, rules={PAIN_HIGH, PAIN_RISING} - {d.rule for d in drafts if d})
    reopened = _reopen(db_session=db_session, session=session, drafts=[d for d in drafts if d is not None])
    rows_out = add_system_suggestions([d for d in drafts if d is not None], patient_id=session.patient_id,
                                      session_id=session.id, db_session=db_session)  # fmt: skip
    rows_out += reopened
    supersede_older(db_session=db_session, session=session, rules={r.rule for r in rows_out})
    return rows_out


def _reopen(*, db_session: Session, session: ExerciseSession, drafts: list[SuggestionDraft]) -> list[Suggestion]:
    """Makes pending again, with the draft's numbers and text, the session's withdrawn (superseded) system
    suggestions of the drafts' rules: an answer changed back brings its advice back instead of none."""
    out = []
    for draft in drafts:
        row = db_session.scalar(select(Suggestion).where(
            Suggestion.session_id == session.id, Suggestion.source == "system", Suggestion.rule == draft.rule,
            Suggestion.status == "superseded"))  # fmt: skip
        if row is None:
            continue
        row.status, row.decided_at, row.created_at = "pending", None, utcnow()
        row.threshold, row.value, row.text = float(draft.threshold), float(draft.value), draft.text
        row.params = draft.params.model_dump(mode="json")
        out.append(row)
    db_session.flush()
    return out


def _withdraw(*, db_session: Session, session: ExerciseSession, rules: set[str]) -> None:
    """Marks 'superseded' the session's pending system suggestions of these rules (their reason no longer holds)."""
    if not rules:
        return
    db_session.execute(
        update(Suggestion)
        .where(Suggestion.session_id == session.id, Suggestion.source == "system", Suggestion.status == "pending",
               Suggestion.rule.in_(sorted(rules)))
        .values(status="superseded", decided_at=utcnow())
        .execution_options(synchronize_session="fetch")
    )  # fmt: skip
