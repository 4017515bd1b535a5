"""Triage for the therapist dashboard: an attention score per patient, its reasons in words, indicator trends.

Pure functions over what backend.session_review.dashboard reads (no DB, no HTTP). now is timezone-aware UTC; the week
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

Reasons and trends are written with a Translator of the therapist's locale (backend.i18n.therapist_translator:
English until a therapist catalogue exists), numbers and dates formatted by Babel.

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

from backend.exercises.library import LIBRARY
from backend.i18n import N_, Translator
from backend.session_texts import reasons
from kinect_agent.analysis.balance import MIN_STANDING_S
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
ENGLISH = Translator("en", therapist=True)  # the therapist pages' language when the caller names none
INDICATOR_NAMES = {"flexibility": N_("Flexibility"), "endurance": N_("Endurance"), "strength": N_("Strength"),
                   "balance": N_("Balance")}  # fmt: skip


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


def _name(slug: str, t: Translator = ENGLISH) -> str:
    """Returns the exercise's name as the library and the pages write it ("squat" -> "Mini squat")."""
    spec = LIBRARY.get(slug)
    return t.gettext(spec.name) if spec is not None else slug.replace("_", " ")


def _shown(before: float, after: float, unit: str, t: Translator) -> tuple[str, str]:
    """Returns two values as a sentence shows them: whole numbers, or one decimal when whole numbers would read
    the same ("fell from 8.5 to 7.5", never "from 8 to 8")."""
    for digits in (0, 1, 2):
        b, a = t.format_number(before, digits), t.format_number(after, digits)
        if b != a:
            return b + unit, a + unit
    return b + unit, a + unit


def _number(x: float, t: Translator) -> str:
    """Returns a number with the decimals it needs (at most 2): 3 -> "3", 3.5 -> "3.5"."""
    return t.format_number(x, next((d for d in (0, 1) if round(x, d) == round(x, 2)), 2))


def _day(day: dt.date, t: Translator) -> str:
    """Returns a day as the reasons write it: "27 Nov" (Babel, in t's locale: "27. Nov." in German)."""
    return t.format_day_month(day)


def _behind_plan(now: dt.datetime, plan: RunningPlan, done: int, t: Translator) -> tuple[float, str | None]:
    plan_start = dt.datetime.combine(plan.started_on, dt.time(), tzinfo=dt.UTC)
    elapsed = (now - max(week_start(now), plan_start)) / WEEK
    expected = plan.per_week * min(max(elapsed, 0.0), 1.0)
    missed = max(0, math.floor(expected) - done)
    if not missed:
        return 0.0, None
    due = math.floor(expected)
    return 40.0 * missed / expected, t.ngettext(
        "Behind this week's plan: %(done)d of the %(num)d session due by now done (%(per_week)d a week planned)",
        "Behind this week's plan: %(done)d of the %(num)d sessions due by now done (%(per_week)d a week planned)",
        due,
        done=done,
        per_week=plan.per_week,
    )


def _inactive(
    now: dt.datetime, plan: RunningPlan, last_session_at: dt.datetime | None, t: Translator
) -> tuple[float, str | None]:
    if last_session_at is None:
        return 50.0, t.gettext("No session at all since the plan started on %(day)s", day=_day(plan.started_on, t))
    days = (now - last_session_at).days
    if days >= 7:
        return 25.0, t.ngettext("No session for %(num)d day", "No session for %(num)d days", days)
    return 0.0, None


def _falling(now: dt.datetime, sessions: Sequence[RecentSession], t: Translator) -> list[tuple[float, str]]:
    recent_from = now - dt.timedelta(days=RECENT_DAYS)
    baseline_from = recent_from - dt.timedelta(days=BASELINE_DAYS)
    found = []
    slugs = sorted({s.exercise_slug for s in sessions if s.exercise_slug})
    for slug in slugs:
        good = [s for s in sessions if s.exercise_slug == slug and s.quality_ok is not False]
        for attr, unit in (("rom_deg", "°"), ("repetitions", "")):
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
                was, now_ = _shown(b, r, unit, t)
                params = {"exercise": _name(slug, t), "was": was, "now": now_, "recent": RECENT_DAYS,
                          "weeks": BASELINE_DAYS // 7}  # fmt: skip
                if attr == "rom_deg":
                    text = t.gettext(
                        "Range of motion of %(exercise)s fell from %(was)s to %(now)s (median of the last %(recent)d "
                        "days against the %(weeks)d weeks before)",
                        **params,
                    )
                else:
                    text = t.gettext(
                        "Repetitions of %(exercise)s fell from %(was)s to %(now)s (median of the last %(recent)d "
                        "days against the %(weeks)d weeks before)",
                        **params,
                    )
                found.append((points, text))
    return found


def _poor_quality(sessions: Sequence[RecentSession], t: Translator) -> tuple[float, str | None]:
    judged = [s for s in sessions if s.quality_ok is not None][-QUALITY_LAST:]
    poor = sum(1 for s in judged if s.quality_ok is False)
    if not poor:
        return 0.0, None
    return 15.0 * poor / len(judged), t.ngettext(
        "%(poor)d of the last %(num)d session recorded with poor tracking quality",
        "%(poor)d of the last %(num)d sessions recorded with poor tracking quality",
        len(judged),
        poor=poor,
    )


def _pain(
    now: dt.datetime, sessions: Sequence[RecentSession], alert_above: int, t: Translator
) -> tuple[float, str | None]:
    recent_from = now - dt.timedelta(days=RECENT_DAYS)
    baseline_from = recent_from - dt.timedelta(days=BASELINE_DAYS)
    said = [(s, s.pain_nrs) for s in sessions if s.pain_nrs is not None]
    recent = [(s, pain) for s, pain in said if s.started_at >= recent_from]
    if not recent:
        return 0.0, None
    worst, worst_pain = max(recent, key=lambda sp: (sp[1], sp[0].started_at))
    if worst_pain > alert_above:
        return 30.0, t.gettext(
            "Said pain %(pain)d of 10 after %(exercise)s on %(day)s (alert above %(alert)d)",
            pain=worst_pain,
            exercise=_name(worst.exercise_slug or "", t),
            day=_day(worst.started_at.date(), t),
            alert=alert_above,
        )
    base = [pain for s, pain in said if baseline_from <= s.started_at < recent_from]
    if len(base) >= 2:
        b, r = float(median(base)), float(median([pain for _, pain in recent]))
        if r - b >= PAIN_RISE:
            return 25.0, t.gettext(
                "Pain after sets rose from %(was)s to %(now)s of 10 (median of the last %(recent)d days against the "
                "%(weeks)d weeks before)",
                was=_number(b, t),
                now=_number(r, t),
                recent=RECENT_DAYS,
                weeks=BASELINE_DAYS // 7,
            )
    return 0.0, None


def _hurt(unread: int, latest: dt.datetime | None, t: Translator) -> tuple[float, str | None]:
    if unread <= 0:
        return 0.0, None
    if latest is None:
        return HURT_REPLY, t.ngettext(
            "Answered advice “It hurt” (unread)", "%(num)d unread “It hurt” answers to advice", unread
        )
    day = _day(latest.astimezone(dt.UTC).date(), t)
    return HURT_REPLY, t.ngettext(
        "Answered advice “It hurt” on %(day)s (unread)",
        "%(num)d unread “It hurt” answers to advice, the latest on %(day)s",
        unread,
        day=day,
    )


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
    t: Translator = ENGLISH,
) -> Attention:
    """Returns the attention score, level and reasons of one patient (module doc); sessions: oldest first;
    pain_alert_above: the patient's pain alert level (0-9; pain above it counts); unread_hurt: the patient's "It
    hurt" replies to advice no therapist has read, the latest sent at last_hurt_at; t: the reader's language."""
    parts: list[tuple[float, str | None]] = []
    new = plan is not None and (now.date() - plan.started_on).days < NEW_PLAN_DAYS
    if plan is not None and plan.per_week > 0:
        parts.append(_behind_plan(now, plan, sessions_this_week, t))
        if not new:
            parts.append(_inactive(now, plan, last_session_at, t))
    parts.append(_poor_quality(sessions, t))
    parts.append(_pain(now, sessions, pain_alert_above, t))
    parts.append(_hurt(unread_hurt, last_hurt_at, t))
    if pending_suggestions:
        points = min(ADVICE_MAX, ADVICE_PER_SUGGESTION * pending_suggestions)
        text = t.ngettext("%(num)d suggestion to review", "%(num)d suggestions to review", pending_suggestions)
        parts.append((points, text))
    falling = _falling(now, sessions, t)
    total = sum(p for p, _ in parts) + max((p for p, _ in falling), default=0.0)
    total = min(100.0, total)
    if new:
        total = min(total, NOW_AT - 1.0)
    score = round(total)
    ranked = sorted([(p, t) for p, t in parts if t] + falling, key=lambda pt: -pt[0])
    reasons = [t for _, t in ranked]
    if plan is not None and new and last_session_at is None:
        reasons.append(t.gettext("New plan since %(day)s; no session yet", day=_day(plan.started_on, t)))
    level = "now" if score >= NOW_AT else "soon" if score >= SOON_AT else "ok"
    return Attention(score=score, level=level, reasons=reasons)


def indicator_trends(
    now: dt.datetime, sessions: Sequence[RecentSession], t: Translator = ENGLISH
) -> dict[str, dict[str, Any]]:
    """Returns per indicator {"weeks", "weekly_median", "direction", "text"} over TREND_WEEKS weeks (module doc);
    text in t's language."""
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
        label = t.gettext(INDICATOR_NAMES[name])
        if len(known) < 2:
            direction = None
            text = t.gettext("%(indicator)s: not enough weeks with data for a trend", indicator=label)
        else:
            (k0, v0), (k1, v1) = known[0], known[-1]
            delta = v1 - v0
            direction = "up" if delta >= TREND_STEP else "down" if delta <= -TREND_STEP else "flat"
            text = _trend_text(direction, label, t.format_number(v0), t.format_number(v1), k1 - k0, t)
        out[name] = {"weeks": weeks, "weekly_median": weekly, "direction": direction, "text": text}
    return out


def _trend_text(direction: str, label: str, was: str, now: str, weeks: int, t: Translator) -> str:
    """Returns an indicator's trend in words: "Balance rose from 40 to 52 over 3 weeks"."""
    params: dict[str, object] = {"indicator": label, "was": was, "now": now}
    if direction == "up":
        return t.ngettext(
            "%(indicator)s rose from %(was)s to %(now)s over %(num)d week",
            "%(indicator)s rose from %(was)s to %(now)s over %(num)d weeks",
            weeks,
            **params,
        )
    if direction == "down":
        return t.ngettext(
            "%(indicator)s fell from %(was)s to %(now)s over %(num)d week",
            "%(indicator)s fell from %(was)s to %(now)s over %(num)d weeks",
            weeks,
            **params,
        )
    return t.ngettext(
        "%(indicator)s held steady from %(was)s to %(now)s over %(num)d week",
        "%(indicator)s held steady from %(was)s to %(now)s over %(num)d weeks",
        weeks,
        **params,
    )


def balance_missing(
    latest_indicators: Indicators | None, exercise_slug: str | None, t: Translator = ENGLISH
) -> str | None:
    """Returns why the latest indicators have no balance score, in words (t's language, the analysis' own reason
    too: backend.session_texts.reasons), or None when they have one."""
    if latest_indicators is None:
        return t.gettext("Not measured: no analysed session yet")
    if latest_indicators.balance.score is not None:
        return None
    missing = latest_indicators.balance.missing
    reason = None if missing is None else reasons.written(missing, t)
    standing = _number(MIN_STANDING_S, t)
    if exercise_slug:
        name = _name(exercise_slug, t)
        if isinstance(reason, str) and reason:
            return t.gettext("Not measured (%(exercise)s): %(reason)s", exercise=name, reason=reason)
        return t.gettext(
            "Not measured: no still standing of %(seconds)s s or more in the last session (%(exercise)s)",
            seconds=standing,
            exercise=name,
        )
    if isinstance(reason, str) and reason:
        return t.gettext("Not measured: %(reason)s", reason=reason)
    return t.gettext("Not measured: no still standing of %(seconds)s s or more in the last session", seconds=standing)
