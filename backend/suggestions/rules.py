"""Explainable coaching rules: each compares one metric of a session against a threshold and says why in plain words.

Pure functions, no database. A draft names the rule (its kind), the metric, the comparison, the threshold and the
measured value, so a therapist can check "value <comparison> threshold" against the session's metrics, and what the
rule found as AdviceParams (the exercise, the days, the numbers). Its text is written for the patient (short
sentences, no jargon, the numbers that matter) and names the exercise and the day of the session ("On Saturday you
did 6 of the 10 sit-to-stands in your plan. ..."): advice_text(rule, metric, params, t) writes it in any language (a
backend.i18n.Translator), so stored advice is shown in the language of whoever reads it, whenever they read it.
"""

from __future__ import annotations

import datetime as dt
import math
import statistics
from dataclasses import dataclass
from typing import Any, Literal, TypeVar

from pydantic import BaseModel, ConfigDict, Field

from backend.exercises.library import LIBRARY
from backend.i18n import ENGLISH, N_, Translator
from backend.sessions.history import HISTORY_WINDOW_DAYS
from kinect_agent.analysis.document import AnalysisReport

# the day of a session in the advice ("on 14 November"), per locale; with " y" appended in another year
DATE_PATTERNS = {"en": "d MMMM", "de": "d. MMMM", "es": "d 'de' MMMM", "fr": "d MMMM"}
YEAR_PATTERNS = {"en": " y", "de": " y", "es": " 'de' y", "fr": " y"}
WEEKDAY_DATE_PATTERNS = {"en": "EEEE d MMMM", "de": "EEEE, d. MMMM", "es": "EEEE d 'de' MMMM", "fr": "EEEE d MMMM"}

# --- rule names (the kind of a suggestion) ---------------------------------------------------------------------
FEWER_REPS = "fewer_reps"
ROM_DROP = "rom_drop"
TOO_FAST = "too_fast"
POOR_DATA_QUALITY = "poor_data_quality"
MISSED_DAYS = "missed_days"
PAIN_HIGH = "pain_high"  # the patient said more pain after a set than their therapist's alert level
PAIN_RISING = "pain_rising"  # the median pain said after sets rose over the last week
RULES = (FEWER_REPS, ROM_DROP, TOO_FAST, POOR_DATA_QUALITY, MISSED_DAYS, PAIN_HIGH, PAIN_RISING)

# --- thresholds ------------------------------------------------------------------------------------------------
ROM_DROP_FRACTION = 0.85  # fires when rom_deg < 0.85 x median rom_deg of the baseline sessions
ROM_BASELINE_WINDOW_DAYS = HISTORY_WINDOW_DAYS  # baseline = earlier good-quality sessions of the last 4 weeks ...
ROM_BASELINE_MIN_SPAN_DAYS = 14  # ... reaching back at least 2 weeks ...
ROM_BASELINE_MIN_SESSIONS = 3  # ... with at least this many sessions
MIN_TEMPO_S_PER_REP = 1.5  # fires when a repetition takes less than this, seconds
ADVISED_TEMPO_S_PER_REP = 2  # what the text asks for instead, seconds
QUALITY_MIN_TRACKED_FRACTION = 0.9  # explains a failed quality check as "step into view" below this
QUALITY_MAX_OUTLIER_FRACTION = 0.05  # explains it as "the camera lost you" above this
ACTIVE_DAYS_WINDOW = 7  # missed days: distinct UTC days with a session among the last 7, today included
WEEKDAY_NAME_DAYS = 7  # a session less than this many days before the advice is named by its weekday, else by date
PAIN_RECENT_DAYS, PAIN_BASELINE_DAYS = 7, 28  # pain rising: the median of the last 7 days against the 28 before
PAIN_RISE_POINTS = 2.0  # ... fires when it rose by this many points of 10 or more (as backend.sessions.triage)
PAIN_BASELINE_MIN = 2  # ... with at least this many answers before the week


class AdviceParams(BaseModel):
    """What a rule found, the inputs of its advice text (stored with the suggestion; version 1). Each rule fills the
    fields its text names; the others stay None."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    version: Literal[1] = 1
    exercise: str | None = Field(default=None, max_length=64, description="the exercise's slug, e.g. 'squat'")
    session_on: dt.date | None = Field(default=None, description="the UTC day of the session the advice is about")
    written_on: dt.date | None = Field(
        default=None, description="the UTC day the advice was written: within a week of it the session is named by "
        "its weekday, else by its date"
    )  # fmt: skip
    repetitions: float | None = None  # counted in the session (fewer_reps)
    goal: int | None = None  # repetitions the plan asks for (fewer_reps)
    rom_deg: float | None = None  # range of motion of the session, degrees (rom_drop)
    baseline_rom_deg: float | None = None  # median range of motion of the weeks before, degrees (rom_drop)
    tempo_s_per_rep: float | None = None  # seconds per repetition (too_fast)
    advised_s_per_rep: int | None = None  # whole seconds per repetition the text asks for (too_fast)
    tracked_fraction: float | None = None  # of the time the camera saw the patient, 0-1 (poor_data_quality)
    pain: int | None = None  # pain said after the set, 0-10 (pain_high)
    active_days: int | None = None  # days with a session in the 7 up to up_to (missed_days)
    expected_days: int | None = None  # days a week the plan asks for (missed_days)
    up_to: dt.date | None = None  # the last of those 7 days (missed_days)
    pain_recent: float | None = None  # median pain of the last week (pain_rising)
    pain_before: float | None = None  # median pain of the weeks before (pain_rising)


@dataclass(frozen=True)
class SessionDay:
    """The UTC day of a session and the day advice about it is written (which decides how the text names it)."""

    on: dt.date
    written_on: dt.date

    @classmethod
    def of(cls, started_at: dt.datetime, today: dt.date) -> SessionDay:
        """Returns the day of a session that started at started_at (timezone-aware), written on today (UTC)."""
        return cls(started_at.astimezone(dt.UTC).date(), today)


@dataclass(frozen=True)
class SuggestionDraft:
    """One fired rule: `value <comparison> threshold` held for `metric`; params: what it found; text: the advice for
    the patient in the language the rule ran in (advice_text writes it in any other)."""

    rule: str
    metric: str
    comparison: str
    threshold: float
    value: float
    params: AdviceParams
    text: str

    @property
    def explanation(self) -> str:
        """Returns the check for a therapist, e.g. 'repetitions 6 < 10'."""
        return f"{self.metric} {self.value:g} {self.comparison} {self.threshold:g}"


# --- words ------------------------------------------------------------------------------------------------------


def exercise_plural(slug: object, t: Translator = ENGLISH) -> str:
    """Returns how the patient counts repetitions of an exercise: 'sit-to-stands', 'mini squats'; 'repetitions'
    for an unknown exercise. In the other languages: the exercise's translated name, which their sentences use as
    a label."""
    spec = LIBRARY.get(slug) if isinstance(slug, str) else None
    if t.locale != ENGLISH.locale:
        return t.gettext(spec.name) if spec is not None else t.gettext("repetitions")
    if spec is None:
        return "repetitions"
    name = spec.name.lower()
    if name == "sit to stand":
        return "sit-to-stands"
    return name if name.endswith("s") else name + "s"


def session_day(started_at: dt.datetime, today: dt.date, t: Translator = ENGLISH) -> str:
    """Returns the day of a session as the advice names it: 'on Saturday' within the last week (UTC days), else
    'on 14 November' (with the year when it is not this year's); in t's language."""
    return day_words(started_at.astimezone(dt.UTC).date(), today, t)


def day_words(day: dt.date, today: dt.date, t: Translator = ENGLISH) -> str:
    """Returns a session's UTC day as advice written on today names it (session_day)."""
    if 0 <= (today - day).days < WEEKDAY_NAME_DAYS:
        return t.gettext(N_("on %(weekday)s"), weekday=t.format_date(day, "EEEE"))
    pattern = DATE_PATTERNS[t.locale] + ("" if day.year == today.year else YEAR_PATTERNS[t.locale])
    return t.gettext(N_("on %(date)s"), date=t.format_date(day, pattern))


def _sentence(text: str) -> str:
    return text[:1].upper() + text[1:]


# --- input checks ----------------------------------------------------------------------------------------------


def _finite(value: float | None) -> float | None:
    """Returns value, or None when it is missing or not finite (a NaN or infinite metric counts as missing)."""
    return value if value is not None and math.isfinite(value) else None


def _aware(value: object, where: str) -> dt.datetime:
    if not isinstance(value, dt.datetime) or value.tzinfo is None or value.utcoffset() is None:
        raise ValueError(f"{where} must be a timezone-aware datetime, got {value!r}")
    return value.astimezone(dt.UTC)


def _positive_int(value: object, where: str) -> int | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ValueError(f"{where} must be a positive integer or None, got {value!r}")
    return value


def _checked_history(history: object) -> list[tuple[dt.datetime, AnalysisReport | None]]:
    if not isinstance(history, list | tuple):
        raise ValueError(f"history must be a list of (datetime, document) pairs, got {type(history).__name__}")
    out = []
    for i, entry in enumerate(history):
        if not isinstance(entry, tuple | list) or len(entry) != 2 or not isinstance(entry[1], AnalysisReport | None):
            raise ValueError(f"history[{i}] must be a (datetime, AnalysisReport or None) pair, got {entry!r:.80}")
        out.append((_aware(entry[0], f"history[{i}][0]"), entry[1]))
    return out


# --- the texts -------------------------------------------------------------------------------------------------


def _draft(rule: str, metric: str, comparison: str, threshold: float, value: float, params: AdviceParams,
           t: Translator) -> SuggestionDraft:  # fmt: skip
    return SuggestionDraft(rule, metric, comparison, float(threshold), float(value), params,
                           advice_text(rule, metric, params, t))  # fmt: skip


T = TypeVar("T")


def _need(value: T | None, name: str, rule: str) -> T:
    if value is None:
        raise ValueError(f"the {rule} advice needs params.{name}")
    return value


def _day(params: AdviceParams, rule: str, t: Translator) -> str:
    on, written = _need(params.session_on, "session_on", rule), _need(params.written_on, "written_on", rule)
    return _sentence(day_words(on, written, t))


def _points(value: float, t: Translator) -> str:
    """Returns a median of pain answers as the text writes it: "4", or "4.5" (this locale's decimal sign)."""
    return t.format_number(value, 0 if value.is_integer() else 1)


def advice_text(rule: str, metric: str, params: AdviceParams, t: Translator = ENGLISH) -> str:
    """Returns the advice of a fired rule in t's language, from what the rule found (metric tells apart the texts of
    a rule). Raises ValueError for an unknown rule or params that lack what its text names."""
    what = exercise_plural(params.exercise, t)
    if rule == FEWER_REPS:
        done, goal = _need(params.repetitions, "repetitions", rule), _need(params.goal, "goal", rule)
        if done == 0:
            return t.gettext(
                N_("%(day)s the camera did not count any %(what)s. Your plan asks for %(goal)s. Please try again, "
                   "and move the way your therapist showed you."),
                day=_day(params, rule, t), what=what, goal=goal,
            )  # fmt: skip
        return t.gettext(
            N_("%(day)s you did %(done)s of the %(goal)s %(what)s in your plan. Next time, try to do all %(goal)s. "
               "Rest for a moment between them if you need to."),
            day=_day(params, rule, t), done=t.format_number(done), goal=goal, what=what,
        )  # fmt: skip
    if rule == ROM_DROP:
        return t.gettext(
            N_("%(day)s your %(what)s were smaller movements than in the last weeks: %(rom)s degrees, while it was "
               "about %(before)s degrees before. Move slowly and go as far as feels comfortable. If it hurts, stop "
               "and tell your therapist."),
            day=_day(params, rule, t), what=what, rom=t.format_number(_need(params.rom_deg, "rom_deg", rule)),
            before=t.format_number(_need(params.baseline_rom_deg, "baseline_rom_deg", rule)),
        )  # fmt: skip
    if rule == TOO_FAST:
        return t.gettext(
            N_("%(day)s you did your %(what)s quickly: about %(tempo)s seconds for each one. Please slow down and "
               "take at least %(advised)s seconds for each one. Slow, steady movements help you more."),
            day=_day(params, rule, t), what=what,
            tempo=t.format_number(_need(params.tempo_s_per_rep, "tempo_s_per_rep", rule), 1),
            advised=_need(params.advised_s_per_rep, "advised_s_per_rep", rule),
        )  # fmt: skip
    if rule == POOR_DATA_QUALITY and metric == "quality.tracked_fraction":
        return t.gettext(
            N_("%(day)s the camera could not see all of you during your %(what)s (it saw you %(percent)s of the "
               "time). Please step into view: stand so that you see your whole body, from head to feet, on the "
               "screen."),
            day=_day(params, rule, t), what=what,
            percent=t.format_percent(_need(params.tracked_fraction, "tracked_fraction", rule)),
        )  # fmt: skip
    if rule == POOR_DATA_QUALITY and metric == "quality.outlier_fraction":
        return t.gettext(
            N_("%(day)s the camera had trouble following your %(what)s. Please make sure the room is well lit, "
               "nothing stands between you and the camera, and the camera points straight at you."),
            day=_day(params, rule, t), what=what,
        )  # fmt: skip
    if rule == POOR_DATA_QUALITY:
        return t.gettext(
            N_("%(day)s the camera could not measure your %(what)s well. Please move the camera so that it faces "
               "you and sees your whole body, then try again."),
            day=_day(params, rule, t), what=what,
        )  # fmt: skip
    if rule == MISSED_DAYS:
        active = _need(params.active_days, "active_days", rule)
        known = params.exercise in LIBRARY
        return t.ngettext(
            "In the 7 days up to %(date)s you did %(what)s on %(num)d day. Your plan asks for %(expected)s days a "
            "week. Try to choose a fixed time of day for your exercises.",
            "In the 7 days up to %(date)s you did %(what)s on %(num)d days. Your plan asks for %(expected)s days a "
            "week. Try to choose a fixed time of day for your exercises.",
            active, date=t.format_date(_need(params.up_to, "up_to", rule), WEEKDAY_DATE_PATTERNS[t.locale]),
            what=what if known else t.gettext(N_("this exercise")),
            expected=_need(params.expected_days, "expected_days", rule),
        )  # fmt: skip
    if rule == PAIN_HIGH:
        return t.gettext(
            N_("%(day)s you said your pain was %(pain)s of 10 after your %(what)s. Do them gently and only as far "
               "as is comfortable. Stop if the pain gets worse, and tell your therapist how you feel."),
            day=_day(params, rule, t), pain=_need(params.pain, "pain", rule), what=what,
        )  # fmt: skip
    if rule == PAIN_RISING:
        return t.gettext(
            N_("In the last week you said more pain after your exercises than before: about %(now)s of 10, while "
               "it was about %(before)s of 10 in the weeks before. Do your exercises gently, and tell your "
               "therapist how you feel."),
            now=_points(_need(params.pain_recent, "pain_recent", rule), t),
            before=_points(_need(params.pain_before, "pain_before", rule), t),
        )  # fmt: skip
    raise ValueError(f"no advice text for rule {rule!r} (metric {metric!r})")


# --- the rules -------------------------------------------------------------------------------------------------


def _about(doc: AnalysisReport, day: SessionDay) -> dict[str, Any]:
    return {"exercise": doc.exercise, "session_on": day.on, "written_on": day.written_on}


def fewer_reps(doc: AnalysisReport, prescribed_reps: int | None, day: SessionDay, t: Translator = ENGLISH
               ) -> SuggestionDraft | None:  # fmt: skip
    """Fires when the session counted fewer repetitions than the plan prescribes."""
    reps = doc.repetitions
    if prescribed_reps is None or reps >= prescribed_reps:
        return None
    params = AdviceParams(**_about(doc, day), repetitions=reps, goal=prescribed_reps)
    return _draft(FEWER_REPS, "repetitions", "<", prescribed_reps, reps, params, t)


def _rom_baseline(history: list[tuple[dt.datetime, AnalysisReport | None]], now: dt.datetime, exercise: str
                  ) -> list[float]:  # fmt: skip
    """Returns rom_deg of the earlier good-quality sessions of the last ROM_BASELINE_WINDOW_DAYS (same exercise)."""
    start = now - dt.timedelta(days=ROM_BASELINE_WINDOW_DAYS)
    times, values = [], []
    for t, past in history:
        if past is None or not start <= t < now or not past.quality.ok or past.exercise != exercise:
            continue
        rom = _finite(past.rom_deg)
        if rom is not None:
            times.append(t)
            values.append(rom)
    if len(values) < ROM_BASELINE_MIN_SESSIONS or now - min(times) < dt.timedelta(days=ROM_BASELINE_MIN_SPAN_DAYS):
        return []
    return values


def rom_drop(
    doc: AnalysisReport,
    history: list[tuple[dt.datetime, AnalysisReport | None]],
    now: dt.datetime,
    day: SessionDay,
    t: Translator = ENGLISH,
) -> SuggestionDraft | None:
    """Fires when rom_deg < ROM_DROP_FRACTION x the median rom_deg of the last 2-4 weeks."""
    rom = _finite(doc.rom_deg)
    baseline = _rom_baseline(history, now, doc.exercise)
    if rom is None or not baseline:
        return None
    median = statistics.median(baseline)
    threshold = ROM_DROP_FRACTION * median
    if rom >= threshold:
        return None
    params = AdviceParams(**_about(doc, day), rom_deg=rom, baseline_rom_deg=median)
    return _draft(ROM_DROP, "rom_deg", "<", threshold, rom, params, t)


def too_fast(doc: AnalysisReport, day: SessionDay, t: Translator = ENGLISH) -> SuggestionDraft | None:
    """Fires when a repetition took less than MIN_TEMPO_S_PER_REP seconds on average."""
    tempo = _finite(doc.tempo_s_per_rep)
    if tempo is None or tempo <= 0 or tempo >= MIN_TEMPO_S_PER_REP:
        return None
    params = AdviceParams(**_about(doc, day), tempo_s_per_rep=tempo, advised_s_per_rep=ADVISED_TEMPO_S_PER_REP)
    return _draft(TOO_FAST, "tempo_s_per_rep", "<", MIN_TEMPO_S_PER_REP, tempo, params, t)


def poor_data_quality(doc: AnalysisReport, day: SessionDay, t: Translator = ENGLISH) -> SuggestionDraft | None:
    """Fires when the analysis found the data unreliable (quality.ok false); says what to change at the camera."""
    if doc.quality.ok:
        return None
    tracked, outliers = _finite(doc.quality.tracked_fraction), _finite(doc.quality.outlier_fraction)
    if tracked is not None and tracked < QUALITY_MIN_TRACKED_FRACTION:
        params = AdviceParams(**_about(doc, day), tracked_fraction=tracked)
        return _draft(POOR_DATA_QUALITY, "quality.tracked_fraction", "<", QUALITY_MIN_TRACKED_FRACTION, tracked,
                      params, t)  # fmt: skip
    params = AdviceParams(**_about(doc, day))
    if outliers is not None and outliers > QUALITY_MAX_OUTLIER_FRACTION:
        return _draft(POOR_DATA_QUALITY, "quality.outlier_fraction", ">", QUALITY_MAX_OUTLIER_FRACTION, outliers,
                      params, t)  # fmt: skip
    return _draft(POOR_DATA_QUALITY, "quality.ok", "==", 0.0, 0.0, params, t)


def missed_days(
    history: list[tuple[dt.datetime, AnalysisReport | None]],
    expected_per_week: int | None,
    now: dt.datetime,
    exercise: str | None = None,
    t: Translator = ENGLISH,
) -> SuggestionDraft | None:
    """Fires when fewer of the last 7 days (today included, UTC) had a session than the plan expects per week.

    Only judged once the patient has sessions from before that week (a first week is never "missed"). A session
    whose stored document no schema reads (None in history) still counts as a day exercised.
    """
    if expected_per_week is None:
        return None
    today = now.date()
    first = today - dt.timedelta(days=ACTIVE_DAYS_WINDOW - 1)
    dates = [t.date() for t, _ in history if t <= now]
    if not dates or min(dates) >= first:
        return None
    active = len({d for d in dates if d >= first} | {today})
    expected = min(expected_per_week, ACTIVE_DAYS_WINDOW)
    if active >= expected:
        return None
    params = AdviceParams(exercise=exercise, active_days=active, expected_days=expected, up_to=today)
    return _draft(MISSED_DAYS, "active_days_last_7d", "<", expected, active, params, t)


def evaluate(
    doc: AnalysisReport,
    *,
    prescribed_reps: int | None,
    history: list[tuple[dt.datetime, AnalysisReport | None]],
    expected_per_week: int | None,
    now: dt.datetime,
    today: dt.date | None = None,
    t: Translator = ENGLISH,
) -> list[SuggestionDraft]:
    """Returns the drafts of every rule that fires for one analysed session.

    doc: the analysis document of the session (kinect_agent.analysis.document; a stored one read with
    read_report). prescribed_reps: repetitions per set of the plan, None = no plan. history: (started_at, document)
    of earlier sessions of the same patient and exercise, document None where no schema reads the stored one
    (backend.sessions.history.session_history). expected_per_week: sessions per week of the plan. now: when the
    session happened (timezone-aware). today: the day the advice is written (UTC), which decides whether the text
    names the session's weekday or its date; defaults to the day of now. t: the language of the drafts' texts
    (English by default).
    When quality.ok is false only the data-quality and missed-days rules run: the measurements are not trusted.
    A metric that is NaN or infinite counts as missing. Raises ValueError naming the argument that is malformed.
    """
    if not isinstance(doc, AnalysisReport):
        raise ValueError(f"doc must be an AnalysisReport (the analysis document), got {type(doc).__name__}")
    now = _aware(now, "now")
    prescribed_reps = _positive_int(prescribed_reps, "prescribed_reps")
    expected_per_week = _positive_int(expected_per_week, "expected_per_week")
    past = _checked_history(history)
    if today is not None and (not isinstance(today, dt.date) or isinstance(today, dt.datetime)):
        raise ValueError(f"today must be a date or None, got {today!r}")
    day = SessionDay.of(now, now.date() if today is None else today)
    if doc.quality.ok:
        drafts = [fewer_reps(doc, prescribed_reps, day, t), rom_drop(doc, past, now, day, t), too_fast(doc, day, t)]
    else:
        drafts = [poor_data_quality(doc, day, t)]
    drafts.append(missed_days(past, expected_per_week, now, doc.exercise, t))
    return [d for d in drafts if d is not None]


# --- how the set felt (run when the patient answers, backend.feeling) ------------------------------------------


def pain_high(pain: int | None, alert_above: int, exercise: str | None, day: SessionDay, t: Translator = ENGLISH
              ) -> SuggestionDraft | None:  # fmt: skip
    """Fires when the pain the patient said after a set (0-10) is above their alert level (0-9, the therapist's)."""
    if pain is None or pain <= alert_above:
        return None
    params = AdviceParams(exercise=exercise, session_on=day.on, written_on=day.written_on, pain=pain)
    return _draft(PAIN_HIGH, "pain_nrs", ">", alert_above, pain, params, t)


def pain_rising(
    answers: list[tuple[dt.datetime, int]], now: dt.datetime, t: Translator = ENGLISH
) -> SuggestionDraft | None:
    """Fires when the median pain said in the PAIN_RECENT_DAYS up to now rose by PAIN_RISE_POINTS or more over the
    median of the PAIN_BASELINE_DAYS before (≥ PAIN_BASELINE_MIN answers). answers: (set started_at, pain 0-10)."""
    now = _aware(now, "now")
    recent_from = now - dt.timedelta(days=PAIN_RECENT_DAYS)
    baseline_from = recent_from - dt.timedelta(days=PAIN_BASELINE_DAYS)
    recent = [p for when, p in answers if recent_from <= _aware(when, "answers[][0]") <= now]
    before = [p for when, p in answers if baseline_from <= _aware(when, "answers[][0]") < recent_from]
    if not recent or len(before) < PAIN_BASELINE_MIN:
        return None
    was, is_ = float(statistics.median(before)), float(statistics.median(recent))
    if is_ - was < PAIN_RISE_POINTS:
        return None
    params = AdviceParams(pain_recent=is_, pain_before=was)
    return _draft(PAIN_RISING, "pain_nrs_median_7d", ">=", was + PAIN_RISE_POINTS, is_, params, t)
