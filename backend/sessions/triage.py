"""Triage for the therapist dashboard: an attention score per patient, its reasons in words, indicator trends.

Pure functions over what backend.sessions.dashboard reads (no DB, no HTTP). now is timezone-aware UTC; the week
starts Monday 00:00 UTC. The attention score is the sum of five parts, clipped to 0..100 and rounded:

    behind plan   A = 40 · missed / expected, where expected = per_week · elapsed / 7 days, elapsed = time since
                  max(Monday 00:00, the running plan's start) (so Monday morning expects nothing yet),
                  missed = max(0, ⌊expected⌋ − sessions this week): a session counts as missed only once a whole
                  one is due; per_week = sessions per week the running plans prescribe.
    inactive      N = 50 when the plan started ≥ 7 days ago and the patient has no session at all (alone "now");
                  N = 25 when the last session is ≥ 7 days old (plan started ≥ 7 days ago); else 0.
    falling       D = max over exercises and over {range of motion, repetitions} of
                  35 · clip((drop − 0.10) / 0.30, 0, 1), drop = (baseline − recent) / baseline, with
                  recent = median over the exercise's sessions of the last RECENT_DAYS (7) days and
                  baseline = median over its sessions of the BASELINE_DAYS (28) days before those, both of
                  sessions of good data quality only; needs ≥ 1 recent and ≥ 2 baseline sessions. A drop up to
                  10 % is noise; 40 % or more scores the full 35.
    data quality  Q = 15 · poor / n over the last n ≤ 5 analysed sessions of the window (quality_ok false).
    advice        P = min(10, 4 · pending system suggestions): advice waiting for the therapist is the
                  therapist's own to-do, not a sign about the patient, so alone it never makes a patient "soon".
    pain          H = 30 when the patient said pain above their alert level (0-9, set by the therapist per patient;
                  PAIN_ALERT_ABOVE (5) when not set) of 10 (numeric rating scale, asked after each set) in the last
                  RECENT_DAYS days; else 25 when the median pain of those days rose by ≥ PAIN_RISE (2) points over
                  the median of the BASELINE_DAYS before (≥ 1 and ≥ 2 answers); else 0.
    it hurt       R = HURT_REPLY (30) when the patient answered advice "It hurt" and no therapist has read that
                  reply yet (reading it clears it); else 0.

    score = clip(A + N + D + Q + P + H + R, 0, 100); a patient whose running plan started less than 7 days ago (a new
    patient) is capped at NOW_AT − 1. Level: "now" at score ≥ NOW_AT (50), "soon" at ≥ SOON_AT (20), else "ok".
    Reasons: one sentence per part that adds points (largest first), plus "no session yet" for a new patient.

Indicator trends: per indicator (flexibility, endurance, strength, balance) the weekly medians of the sessions'
indicator scores over the TREND_WEEKS (6) weeks ending with the current one (None for a week without a score);
direction "up"/"down" when the latest week with data differs from the earliest by ≥ TREND_STEP (5) points, else
"flat"; None with fewer than two weeks of data.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from statistics import median
from typing import Any

from backend.analysis.balance import MIN_STANDING_S
from backend.exercises.library import EXERCISES
from kinect_agent.analysis.document import Indicators

INDICATORS = ("flexibility", "endurance", "strength", "balance")
NOW_AT, SOON_AT = 50, 20
RECENT_DAYS, BASELINE_DAYS = 7, 28
TREND_WEEKS, TREND_STEP = 6, 5.0
QUALITY_LAST = 5
NEW_PLAN_DAYS = 7
ADVICE_PER_SUGGESTION, ADVICE_MAX = 4.0, 10.0  # advice to review alone stays below SOON_AT
PAIN_ALERT_ABOVE = 5  # pain said after a set (0-10) above this raises attention, unless the therapist set another
PAIN_RISE = 2.0  # a rise of the median pain this large (points of 10) raises attention
HURT_REPLY = 30.0  # an unread "It hurt" reply to advice raises attention as much as pain above the alert level
WEEK = dt.timedelta(days=7)


@dataclass(frozen=True)
class RecentSession:
    """One analysed session of the trend window (the dashboard's third query)."""

    started_at: dt.datetime
    exercise_slug: str | None
    repetitions: int | None
    rom_deg: float | None
    quality_ok: bool | None
    indicator_scores: dict[str, Any] | None  # {indicator: score 0-100 or None}; None: the session has no indicators
    pain_nrs: int | None = None  # pain 0-10 the patient said after the set (backend.feeling); None: not said


@dataclass(frozen=True)
class RunningPlan:
    """The running plans of a patient: sessions per week they prescribe and the earliest start among them."""

    per_week: int
    started_on: dt.date


@dataclass(frozen=True)
class Attention:
    """How much a patient needs the therapist now: score 0..100, level and reasons in words."""

    score: int
    level: str
    reasons: list[str] = field(default_factory=list)


def week_start(now: dt.datetime) -> dt.datetime:
    """Returns Monday 00:00 UTC of the week that contains now (timezone-aware)."""
    day = now.astimezone(dt.UTC).date()
    monday = day - dt.timedelta(days=day.weekday())
    return dt.datetime.combine(monday, dt.time(), tzinfo=dt.UTC)


def window_start(now: dt.datetime) -> dt.datetime:
    """Returns the start of the sessions the triage reads: Monday of the oldest trend week (≥ 35 days back)."""
    return week_start(now) - (TREND_WEEKS - 1) * WEEK


def _name(slug: str) -> str:
    """Returns the exercise's name as the library and the pages write it ("squat" -> "Mini squat")."""
    spec = EXERCISES.get(slug)
    return spec.name if spec is not None else slug.replace("_", " ")


def _shown(before: float, after: float, unit: str) -> tuple[str, str]:
    """Returns two values as a sentence shows them: whole numbers, or one decimal when whole numbers would read
    the same ("fell from 8.5 to 7.5", never "from 8 to 8")."""
    for digits in (0, 1, 2):
        b, a = f"{before:.{digits}f}", f"{after:.{digits}f}"
        if b != a:
            return b + unit, a + unit
    return b + unit, a + unit


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def _fmt_date(day: dt.date) -> str:
    return f"{day.day} {day.strftime('%b')}"


def _behind_plan(now: dt.datetime, plan: RunningPlan, done: int) -> tuple[float, str | None]:
    plan_start = dt.datetime.combine(plan.started_on, dt.time(), tzinfo=dt.UTC)
    elapsed = (now - max(week_start(now), plan_start)) / WEEK
    expected = plan.per_week * min(max(elapsed, 0.0), 1.0)
    missed = max(0, math.floor(expected) - done)
    if not missed:
        return 0.0, None
    due = math.floor(expected)
    return 40.0 * missed / expected, (
        f"Behind this week's plan: {done} of the {_plural(due, 'session')} due by now done "
        f"({plan.per_week} a week planned)"
    )


def _inactive(now: dt.datetime, plan: RunningPlan, last_session_at: dt.datetime | None) -> tuple[float, str | None]:
    if last_session_at is None:
        return 50.0, f"No session at all since the plan started on {_fmt_date(plan.started_on)}"
    days = (now - last_session_at).days
    if days >= 7:
        return 25.0, f"No session for {days} days"
    return 0.0, None


def _falling(now: dt.datetime, sessions: Sequence[RecentSession]) -> list[tuple[float, str]]:
    recent_from = now - dt.timedelta(days=RECENT_DAYS)
    baseline_from = recent_from - dt.timedelta(days=BASELINE_DAYS)
    found = []
    slugs = sorted({s.exercise_slug for s in sessions if s.exercise_slug})
    for slug in slugs:
        good = [s for s in sessions if s.exercise_slug == slug and s.quality_ok is not False]
        for attr, label, unit in (("rom_deg", "Range of motion", "°"), ("repetitions", "Repetitions", "")):
            recent = [getattr(s, attr) for s in good if s.started_at >= recent_from and getattr(s, attr) is not None]
            base = [
                getattr(s, attr)
                for s in good
                if baseline_from <= s.started_at < recent_from and getattr(s, attr) is not None
            ]
            if not recent or len(base) < 2:
                continue
            b, r = float(median(base)), float(median(recent))
            if b <= 0:
                continue
            points = 35.0 * min(max(((b - r) / b - 0.10) / 0.30, 0.0), 1.0)
            if points > 0:
                was, now_ = _shown(b, r, unit)
                found.append(
                    (
                        points,
                        f"{label} of {_name(slug)} fell from {was} to {now_} "
                        f"(median of the last {RECENT_DAYS} days against the {BASELINE_DAYS // 7} weeks before)",
                    )
                )
    return found


def _poor_quality(sessions: Sequence[RecentSession]) -> tuple[float, str | None]:
    judged = [s for s in sessions if s.quality_ok is not None][-QUALITY_LAST:]
    poor = sum(1 for s in judged if s.quality_ok is False)
    if not poor:
        return 0.0, None
    return 15.0 * poor / len(judged), (
        f"{poor} of the last {_plural(len(judged), 'session')} recorded with poor tracking quality"
    )


def _pain(now: dt.datetime, sessions: Sequence[RecentSession], alert_above: int) -> tuple[float, str | None]:
    recent_from = now - dt.timedelta(days=RECENT_DAYS)
    baseline_from = recent_from - dt.timedelta(days=BASELINE_DAYS)
    said = [(s, s.pain_nrs) for s in sessions if s.pain_nrs is not None]
    recent = [(s, pain) for s, pain in said if s.started_at >= recent_from]
    if not recent:
        return 0.0, None
    worst, worst_pain = max(recent, key=lambda sp: (sp[1], sp[0].started_at))
    if worst_pain > alert_above:
        day = _fmt_date(worst.started_at.date())
        return 30.0, (f"Said pain {worst_pain} of 10 after {_name(worst.exercise_slug or '')} on {day} "
                      f"(alert above {alert_above})")  # fmt: skip
    base = [pain for s, pain in said if baseline_from <= s.started_at < recent_from]
    if len(base) >= 2:
        b, r = float(median(base)), float(median([pain for _, pain in recent]))
        if r - b >= PAIN_RISE:
            return 25.0, (f"Pain after sets rose from {b:g} to {r:g} of 10 (median of the last {RECENT_DAYS} days "
                          f"against the {BASELINE_DAYS // 7} weeks before)")  # fmt: skip
    return 0.0, None


def _hurt(unread: int, latest: dt.datetime | None) -> tuple[float, str | None]:
    if unread <= 0:
        return 0.0, None
    day = f" on {_fmt_date(latest.astimezone(dt.UTC).date())}" if latest is not None else ""
    if unread == 1:
        return HURT_REPLY, f"Answered advice “It hurt”{day} (unread)"
    return HURT_REPLY, f"{unread} unread “It hurt” answers to advice, the latest{day}"


def attention(
    *,
    now: dt.datetime,
    plan: RunningPlan | None,
    sessions_this_week: int,
    last_session_at: dt.datetime | None,
    sessions: Sequence[RecentSession],
    pending_suggestions: int,
    pain_alert_above: int = PAIN_ALERT_ABOVE,
    unread_hurt: int = 0,
    last_hurt_at: dt.datetime | None = None,
) -> Attention:
    """Returns the attention score, level and reasons of one patient (module doc); sessions: oldest first;
    pain_alert_above: the patient's pain alert level (0-9; pain above it counts); unread_hurt: the patient's "It
    hurt" replies to advice no therapist has read, the latest sent at last_hurt_at."""
    parts: list[tuple[float, str | None]] = []
    new = plan is not None and (now.date() - plan.started_on).days < NEW_PLAN_DAYS
    if plan is not None and plan.per_week > 0:
        parts.append(_behind_plan(now, plan, sessions_this_week))
        if not new:
            parts.append(_inactive(now, plan, last_session_at))
    parts.append(_poor_quality(sessions))
    parts.append(_pain(now, sessions, pain_alert_above))
    parts.append(_hurt(unread_hurt, last_hurt_at))
    if pending_suggestions:
        points = min(ADVICE_MAX, ADVICE_PER_SUGGESTION * pending_suggestions)
        parts.append((points, f"{_plural(pending_suggestions, 'suggestion')} to review"))
    falling = _falling(now, sessions)
    total = sum(p for p, _ in parts) + max((p for p, _ in falling), default=0.0)
    total = min(100.0, total)
    if new:
        total = min(total, NOW_AT - 1.0)
    score = round(total)
    ranked = sorted([(p, t) for p, t in parts if t] + falling, key=lambda pt: -pt[0])
    reasons = [t for _, t in ranked]
    if plan is not None and new and last_session_at is None:
        reasons.append(f"New plan since {_fmt_date(plan.started_on)}; no session yet")
    level = "now" if score >= NOW_AT else "soon" if score >= SOON_AT else "ok"
    return Attention(score=score, level=level, reasons=reasons)


def indicator_trends(now: dt.datetime, sessions: Sequence[RecentSession]) -> dict[str, dict[str, Any]]:
    """Returns per indicator {"weeks", "weekly_median", "direction", "text"} over TREND_WEEKS weeks (module doc)."""
    first = window_start(now)
    weeks = [(first + k * WEEK).date() for k in range(TREND_WEEKS)]
    scores: dict[str, list[list[float]]] = {k: [[] for _ in weeks] for k in INDICATORS}
    for s in sessions:
        k = int((s.started_at - first) // WEEK)
        if not 0 <= k < TREND_WEEKS or not isinstance(s.indicator_scores, dict):
            continue
        for name in INDICATORS:
            score = s.indicator_scores.get(name)
            if isinstance(score, int | float) and math.isfinite(score):
                scores[name][k].append(float(score))
    out = {}
    for name in INDICATORS:
        weekly = [round(float(median(v)), 1) if v else None for v in scores[name]]
        known = [(k, v) for k, v in enumerate(weekly) if v is not None]
        label = name.capitalize()
        if len(known) < 2:
            direction = None
            text = f"{label}: not enough weeks with data for a trend"
        else:
            (k0, v0), (k1, v1) = known[0], known[-1]
            delta = v1 - v0
            direction = "up" if delta >= TREND_STEP else "down" if delta <= -TREND_STEP else "flat"
            verb = {"up": "rose", "down": "fell", "flat": "held steady"}[direction]
            text = f"{label} {verb} from {v0:.0f} to {v1:.0f} over {_plural(k1 - k0, 'week')}"
        out[name] = {"weeks": weeks, "weekly_median": weekly, "direction": direction, "text": text}
    return out


def balance_missing(latest_indicators: Indicators | None, exercise_slug: str | None) -> str | None:
    """Returns why the latest indicators have no balance score, in words, or None when they have one."""
    if latest_indicators is None:
        return "Not measured: no analysed session yet"
    if latest_indicators.balance.score is not None:
        return None
    during = f" ({_name(exercise_slug)})" if exercise_slug else ""
    reason = latest_indicators.balance.missing
    if reason:
        return f"Not measured{during}: {reason}"
    return f"Not measured: no still standing of {MIN_STANDING_S:g} s or more in the last session{during}"
