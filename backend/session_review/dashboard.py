"""Per-patient views over stored sessions: progress series and the therapist dashboard summary.

Summaries of many patients cost three queries (no query per patient), read the indexed scalar columns
of session_metric and only the "indicators" part of a document, and never load the stored files. The attention
score, its reasons and the indicator trends are computed from them by backend.sessions.triage (formula there).
It sits above backend.sessions and backend.suggestions because the attention counts pending suggestions.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Sequence
from typing import Any

from sqlalchemy import ScalarSelect, func, or_, select
from sqlalchemy.orm import Session, aliased

from backend.exercises.models import Exercise
from backend.feeling.models import SessionFeeling
from backend.i18n import Translator
from backend.plans.models import Plan, PlanItem
from backend.replies.models import AdviceReply
from backend.session_texts import reasons
from backend.sessions import triage
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.sessions.triage import week_start
from backend.suggestions.models import Suggestion
from backend.users.models import User
from kinect_agent.analysis.document import Indicators, read_indicators

RANKED_PATIENTS_MAX = 500  # the dashboard ranks up to this many visible patients by attention, beyond it pages by id


def progress(
    *,
    db_session: Session,
    patient_id: int,
    exercise_id: int | None,
    since: dt.datetime | None,
    t: Translator = triage.ENGLISH,
) -> list[dict[str, Any]]:
    """Returns one point per session of the patient (optionally one exercise, since a time), oldest first.

    Each point: session_id, exercise_slug, started_at, repetitions, rom_deg (deg), quality_ok, indicators (why
    balance is missing in t's language), and what the patient said after the set: pain_nrs (0-10), effort_cr10
    (Borg CR10, 0-10); None = not said.
    """
    query = (
        select(
            ExerciseSession.id,
            Exercise.slug,
            ExerciseSession.started_at,
            SessionMetric.repetitions,
            SessionMetric.rom_deg,
            SessionMetric.quality_ok,
            SessionMetric.document["indicators"],
            SessionFeeling.pain_nrs,
            SessionFeeling.effort_cr10,
        )
        .select_from(ExerciseSession)
        .outerjoin(Exercise, Exercise.id == ExerciseSession.exercise_id)
        .outerjoin(SessionMetric, SessionMetric.session_id == ExerciseSession.id)
        .outerjoin(SessionFeeling, SessionFeeling.session_id == ExerciseSession.id)
        .where(ExerciseSession.patient_id == patient_id)
    )
    if exercise_id is not None:
        query = query.where(ExerciseSession.exercise_id == exercise_id)
    if since is not None:
        query = query.where(ExerciseSession.started_at >= since)
    rows = db_session.execute(query.order_by(ExerciseSession.started_at, ExerciseSession.id)).all()
    keys = ("session_id", "exercise_slug", "started_at", "repetitions", "rom_deg", "quality_ok", "indicators",
            "pain_nrs", "effort_cr10")  # fmt: skip
    return [dict(zip(keys, row, strict=True)) | {"indicators": _indicators(row[6], t)} for row in rows]


def _indicators(stored: object, t: Translator) -> Indicators | None:
    """Returns the stored indicators of a document (any schema version) with their reason in t's language."""
    indicators = read_indicators(stored)
    return None if indicators is None else reasons.indicators_with_text(indicators, t)


def _newest_session(*, with_metrics: bool) -> ScalarSelect[int]:
    """Returns a scalar subquery correlated to User: the patient's newest session id (with metrics, if asked).

    ORDER BY started_at DESC, id DESC LIMIT 1 walks the (patient_id, started_at, id) index backwards from the newest
    row, so the cost does not grow with the patient's number of sessions.
    """
    newest = select(ExerciseSession.id).where(ExerciseSession.patient_id == User.id)
    if with_metrics:
        newest = newest.join(SessionMetric, SessionMetric.session_id == ExerciseSession.id)
    return (
        newest.order_by(ExerciseSession.started_at.desc(), ExerciseSession.id.desc())
        .limit(1)
        .correlate(User)
        .scalar_subquery()
    )


def _per_patient(
    db_session: Session, patient_ids: Sequence[int], now: dt.datetime, t: Translator
) -> dict[int, dict[str, Any]]:
    """Returns per patient (one query): last session (brief), latest indicators (their reason in t's language),
    sessions this week, pending advice, unread replies (and how many of them say "It hurt", the latest when), the
    pain alert level."""
    this_week = (
        select(func.count())
        .select_from(ExerciseSession)
        .where(ExerciseSession.patient_id == User.id, ExerciseSession.started_at >= week_start(now))
        .correlate(User)
        .scalar_subquery()
    )
    pending = (
        select(func.count())
        .select_from(Suggestion)
        .where(Suggestion.patient_id == User.id, Suggestion.source == "system", Suggestion.status == "pending")
        .correlate(User)
        .scalar_subquery()
    )
    unread = (
        select(func.count())
        .select_from(AdviceReply)
        .where(AdviceReply.patient_id == User.id, AdviceReply.read_at.is_(None))
        .correlate(User)
        .scalar_subquery()
    )

    def unread_hurt(column: Any) -> ScalarSelect[Any]:
        return (
            select(column)
            .select_from(AdviceReply)
            .where(AdviceReply.patient_id == User.id, AdviceReply.read_at.is_(None), AdviceReply.preset == "hurt")
            .correlate(User)
            .scalar_subquery()
        )

    per = (
        select(
            User.id.label("pid"),
            _newest_session(with_metrics=False).label("sid"),
            _newest_session(with_metrics=True).label("mid"),
            this_week.label("this_week"),
            pending.label("pending"),
            unread.label("unread"),
            unread_hurt(func.count()).label("unread_hurt"),
            unread_hurt(func.max(AdviceReply.created_at)).label("last_hurt_at"),
            User.pain_alert_above.label("pain_alert_above"),
        )
        .where(User.id.in_(patient_ids))
        .subquery()
    )
    last_metric, indicator_metric = aliased(SessionMetric), aliased(SessionMetric)
    rows = db_session.execute(
        select(
            per.c.pid,
            per.c.this_week,
            per.c.pending,
            per.c.unread,
            per.c.unread_hurt,
            per.c.last_hurt_at,
            per.c.pain_alert_above,
            ExerciseSession.id,
            Exercise.slug,
            ExerciseSession.started_at,
            last_metric.repetitions,
            last_metric.rom_deg,
            last_metric.quality_ok,
            indicator_metric.document["indicators"],
        )
        .select_from(per)
        .outerjoin(ExerciseSession, ExerciseSession.id == per.c.sid)
        .outerjoin(Exercise, Exercise.id == ExerciseSession.exercise_id)
        .outerjoin(last_metric, last_metric.session_id == per.c.sid)
        .outerjoin(indicator_metric, indicator_metric.session_id == per.c.mid)
    ).all()
    keys = ("id", "exercise_slug", "started_at", "repetitions", "rom_deg", "quality_ok")
    return {
        pid: {
            "last_session": dict(zip(keys, last, strict=True)) if last[0] is not None else None,
            "sessions_this_week": this_week or 0,
            "pending_suggestions": pending or 0,
            "unread_replies": unread or 0,
            "unread_hurt": hurt or 0,
            "last_hurt_at": hurt_at,
            "latest_indicators": _indicators(indicators, t),
            "pain_alert_above": triage.PAIN_ALERT_ABOVE if alert is None else alert,
        }
        for pid, this_week, pending, unread, hurt, hurt_at, alert, *last, indicators in rows
    }


def _running_plans(db_session: Session, patient_ids: Sequence[int], on: dt.date) -> dict[int, triage.RunningPlan]:
    """Returns per patient with a running plan: per exercise the newest plan's frequency, summed, and its start."""
    rows = db_session.execute(
        select(Plan.patient_id, PlanItem.exercise_id, PlanItem.frequency_per_week, Plan.start_date)
        .join(Plan, Plan.id == PlanItem.plan_id)
        .where(
            Plan.patient_id.in_(patient_ids),
            Plan.start_date <= on,
            or_(Plan.end_date.is_(None), Plan.end_date >= on),
        )
        .order_by(Plan.start_date.desc(), Plan.id.desc(), PlanItem.position)
    ).all()
    chosen: dict[tuple[int, int], tuple[int, dt.date]] = {}
    for pid, exercise_id, per_week, start in rows:
        chosen.setdefault((pid, exercise_id), (per_week, start))
    plans: dict[int, triage.RunningPlan] = {}
    for (pid, _), (per_week, start) in chosen.items():
        before = plans.get(pid)
        plans[pid] = triage.RunningPlan(
            per_week=per_week + (before.per_week if before else 0),
            started_on=min(start, before.started_on) if before else start,
        )
    return plans


def _recent_sessions(
    db_session: Session, patient_ids: Sequence[int], since: dt.datetime
) -> dict[int, list[triage.RecentSession]]:
    """Returns per patient the analysed sessions started since `since`, oldest first (one query)."""
    rows = db_session.execute(
        select(
            ExerciseSession.patient_id,
            ExerciseSession.started_at,
            Exercise.slug,
            SessionMetric.repetitions,
            SessionMetric.rom_deg,
            SessionMetric.quality_ok,
            SessionMetric.indicator_scores,
            SessionFeeling.pain_nrs,
        )
        .select_from(ExerciseSession)
        .join(SessionMetric, SessionMetric.session_id == ExerciseSession.id)
        .outerjoin(Exercise, Exercise.id == ExerciseSession.exercise_id)
        .outerjoin(SessionFeeling, SessionFeeling.session_id == ExerciseSession.id)
        .where(ExerciseSession.patient_id.in_(patient_ids), ExerciseSession.started_at >= since)
        .order_by(ExerciseSession.patient_id, ExerciseSession.started_at, ExerciseSession.id)
    ).all()
    out: dict[int, list[triage.RecentSession]] = {}
    for pid, started_at, slug, reps, rom, quality_ok, indicators, pain in rows:
        out.setdefault(pid, []).append(
            triage.RecentSession(
                started_at=started_at,
                exercise_slug=slug,
                repetitions=reps,
                rom_deg=rom,
                quality_ok=quality_ok,
                indicator_scores=indicators if isinstance(indicators, dict) else None,
                pain_nrs=pain,
            )
        )
    return out


def summaries(
    *, db_session: Session, patient_ids: Sequence[int], now: dt.datetime, t: Translator = triage.ENGLISH
) -> dict[int, dict[str, Any]]:
    """Returns the dashboard summary of each patient (SummaryOut fields) in three queries, whatever their number;
    reasons and trends in t's language (the therapist's: backend.i18n.therapist_translator)."""
    ids = sorted(set(patient_ids))
    if not ids:
        return {}
    per = _per_patient(db_session, ids, now, t)
    plans = _running_plans(db_session, ids, now.astimezone(dt.UTC).date())
    recent = _recent_sessions(db_session, ids, triage.window_start(now))
    empty = {"last_session": None, "sessions_this_week": 0, "pending_suggestions": 0, "unread_replies": 0,
             "unread_hurt": 0, "last_hurt_at": None, "latest_indicators": None,
             "pain_alert_above": triage.PAIN_ALERT_ABOVE}  # fmt: skip
    out = {}
    for pid in ids:
        row = {"patient_id": pid, **empty, **per.get(pid, {})}
        plan, sessions, last = plans.get(pid), recent.get(pid, []), row["last_session"]
        score = triage.attention(
            now=now,
            plan=plan,
            sessions_this_week=row["sessions_this_week"],
            last_session_at=last["started_at"] if last else None,
            sessions=sessions,
            pending_suggestions=row["pending_suggestions"],
            pain_alert_above=row["pain_alert_above"],
            unread_hurt=row.pop("unread_hurt"),
            last_hurt_at=row.pop("last_hurt_at"),
            t=t,
        )
        analysed_slug = next((s.exercise_slug for s in reversed(sessions) if s.indicator_scores is not None), None)
        out[pid] = {
            **row,
            "planned_this_week": plan.per_week if plan else None,
            "attention_score": score.score,
            "attention_level": score.level,
            "attention_reasons": score.reasons,
            "indicator_trends": triage.indicator_trends(now, sessions, t),
            "balance_missing": triage.balance_missing(row["latest_indicators"], analysed_slug, t),
        }
    return out
