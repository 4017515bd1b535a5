"""Explainable coaching rules: each compares one metric of a session against a threshold and says why in plain words.

Pure functions, no database. A draft names the rule (its kind), the metric, the comparison, the threshold and the
measured value, so a therapist can check "value <comparison> threshold" against the session's metrics; its text is
written for the patient (short sentences, no jargon, the numbers that matter) and names the exercise and the day of
the session ("On Saturday you did 6 of the 10 sit-to-stands in your plan. ...").
"""

from __future__ import annotations

import datetime as dt
import math
import statistics
from dataclasses import dataclass

from backend.exercises.library import EXERCISES

# --- rule names (the kind of a suggestion) ---------------------------------------------------------------------
FEWER_REPS = "fewer_reps"
ROM_DROP = "rom_drop"
TOO_FAST = "too_fast"
POOR_DATA_QUALITY = "poor_data_quality"
MISSED_DAYS = "missed_days"
RULES = (FEWER_REPS, ROM_DROP, TOO_FAST, POOR_DATA_QUALITY, MISSED_DAYS)

# --- thresholds ------------------------------------------------------------------------------------------------
ROM_DROP_FRACTION = 0.85  # fires when rom_deg < 0.85 x median rom_deg of the baseline sessions
ROM_BASELINE_WINDOW_DAYS = 28  # baseline = earlier good-quality sessions of the last 4 weeks ...
ROM_BASELINE_MIN_SPAN_DAYS = 14  # ... reaching back at least 2 weeks ...
ROM_BASELINE_MIN_SESSIONS = 3  # ... with at least this many sessions
MIN_TEMPO_S_PER_REP = 1.5  # fires when a repetition takes less than this, seconds
ADVISED_TEMPO_S_PER_REP = 2  # what the text asks for instead, seconds
QUALITY_MIN_TRACKED_FRACTION = 0.9  # explains a failed quality check as "step into view" below this
QUALITY_MAX_OUTLIER_FRACTION = 0.05  # explains it as "the camera lost you" above this
ACTIVE_DAYS_WINDOW = 7  # missed days: distinct UTC days with a session among the last 7, today included
WEEKDAY_NAME_DAYS = 7  # a session less than this many days before the advice is named by its weekday, else by date


@dataclass(frozen=True)
class SuggestionDraft:
    """One fired rule: `value <comparison> threshold` held for `metric`; text is the advice for the patient."""

    rule: str
    metric: str
    comparison: str
    threshold: float
    value: float
    text: str

    @property
    def explanation(self) -> str:
        """Returns the check for a therapist, e.g. 'repetitions 6 < 10'."""
        return f"{self.metric} {self.value:g} {self.comparison} {self.threshold:g}"


# --- words ------------------------------------------------------------------------------------------------------


def exercise_plural(slug: object) -> str:
    """Returns how the patient counts repetitions of an exercise: 'sit-to-stands', 'mini squats'; 'repetitions'
    for an unknown exercise."""
    spec = EXERCISES.get(slug) if isinstance(slug, str) else None
    if spec is None:
        return "repetitions"
    name = spec.name.lower()
    if name == "sit to stand":
        return "sit-to-stands"
    return name if name.endswith("s") else name + "s"


def session_day(started_at: dt.datetime, today: dt.date) -> str:
    """Returns the day of a session as the advice names it: 'on Saturday' within the last week (UTC days), else
    'on 14 November' (with the year when it is not this year's)."""
    day = started_at.astimezone(dt.UTC).date()
    if 0 <= (today - day).days < WEEKDAY_NAME_DAYS:
        return f"on {day:%A}"
    return f"on {day.day} {day:%B}" + ("" if day.year == today.year else f" {day.year}")


def _sentence(text: str) -> str:
    return text[:1].upper() + text[1:]


# --- input checks ----------------------------------------------------------------------------------------------


def _number(doc: dict, key: str, where: str = "doc") -> float | None:
    """Returns doc[key] as a float; None when missing, null or not finite; ValueError when not a number."""
    value = doc.get(key)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{where}[{key!r}] must be a number or null, got {type(value).__name__} {value!r}")
    value = float(value)
    return value if math.isfinite(value) else None


def _quality(doc: dict, where: str = "doc") -> dict:
    quality = doc.get("quality")
    if quality is None:
        return {}
    if not isinstance(quality, dict):
        raise ValueError(f"{where}['quality'] must be an object or null, got {type(quality).__name__}")
    ok = quality.get("ok")
    if ok is not None and not isinstance(ok, bool):
        raise ValueError(f"{where}['quality']['ok'] must be true, false or null, got {ok!r}")
    return quality


def _quality_ok(doc: dict, where: str = "doc") -> bool:
    """Returns False only when the analysis said quality.ok is false (missing or null counts as ok)."""
    return _quality(doc, where).get("ok") is not False


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


def _checked_history(history: object) -> list[tuple[dt.datetime, dict]]:
    if not isinstance(history, list | tuple):
        raise ValueError(f"history must be a list of (datetime, dict), got {type(history).__name__}")
    out = []
    for i, entry in enumerate(history):
        if not isinstance(entry, tuple | list) or len(entry) != 2 or not isinstance(entry[1], dict):
            raise ValueError(f"history[{i}] must be a (datetime, dict) pair, got {entry!r:.80}")
        out.append((_aware(entry[0], f"history[{i}][0]"), entry[1]))
    return out


# --- the rules -------------------------------------------------------------------------------------------------


def fewer_reps(doc: dict, prescribed_reps: int | None, day: str) -> SuggestionDraft | None:
    """Fires when the session counted fewer repetitions than the plan prescribes; day: 'on Saturday'."""
    reps = _number(doc, "repetitions")
    if prescribed_reps is None or reps is None or reps >= prescribed_reps:
        return None
    what = exercise_plural(doc.get("exercise"))
    if reps == 0:
        text = (
            f"{_sentence(day)} the camera did not count any {what}. Your plan asks for {prescribed_reps}. "
            "Please try again, and move the way your therapist showed you."
        )
    else:
        text = (
            f"{_sentence(day)} you did {reps:.0f} of the {prescribed_reps} {what} in your plan. "
            f"Next time, try to do all {prescribed_reps}. Rest for a moment between them if you need to."
        )
    return SuggestionDraft(FEWER_REPS, "repetitions", "<", float(prescribed_reps), reps, text)


def _rom_baseline(history: list[tuple[dt.datetime, dict]], now: dt.datetime, exercise: object) -> list[float]:
    """Returns rom_deg of the earlier good-quality sessions of the last ROM_BASELINE_WINDOW_DAYS (same exercise)."""
    start = now - dt.timedelta(days=ROM_BASELINE_WINDOW_DAYS)
    times, values = [], []
    for i, (t, past) in enumerate(history):
        if not start <= t < now or not _quality_ok(past, f"history[{i}][1]"):
            continue
        if exercise is not None and past.get("exercise") not in (None, exercise):
            continue
        rom = _number(past, "rom_deg", f"history[{i}][1]")
        if rom is not None:
            times.append(t)
            values.append(rom)
    if len(values) < ROM_BASELINE_MIN_SESSIONS or now - min(times) < dt.timedelta(days=ROM_BASELINE_MIN_SPAN_DAYS):
        return []
    return values


def rom_drop(doc: dict, history: list[tuple[dt.datetime, dict]], now: dt.datetime, day: str) -> SuggestionDraft | None:
    """Fires when rom_deg < ROM_DROP_FRACTION x the median rom_deg of the last 2-4 weeks; day: 'on Saturday'."""
    rom = _number(doc, "rom_deg")
    baseline = _rom_baseline(history, now, doc.get("exercise"))
    if rom is None or not baseline:
        return None
    median = statistics.median(baseline)
    threshold = ROM_DROP_FRACTION * median
    if rom >= threshold:
        return None
    text = (
        f"{_sentence(day)} your {exercise_plural(doc.get('exercise'))} were smaller movements than in the last "
        f"weeks: {rom:.0f} degrees, while it was about {median:.0f} degrees before. Move slowly and go as far as "
        "feels comfortable. If it hurts, stop and tell your therapist."
    )
    return SuggestionDraft(ROM_DROP, "rom_deg", "<", threshold, rom, text)


def too_fast(doc: dict, day: str) -> SuggestionDraft | None:
    """Fires when a repetition took less than MIN_TEMPO_S_PER_REP seconds on average; day: 'on Saturday'."""
    tempo = _number(doc, "tempo_s_per_rep")
    if tempo is None or tempo <= 0 or tempo >= MIN_TEMPO_S_PER_REP:
        return None
    text = (
        f"{_sentence(day)} you did your {exercise_plural(doc.get('exercise'))} quickly: about {tempo:.1f} seconds "
        f"for each one. Please slow down and take at least {ADVISED_TEMPO_S_PER_REP} seconds for each one. "
        "Slow, steady movements help you more."
    )
    return SuggestionDraft(TOO_FAST, "tempo_s_per_rep", "<", MIN_TEMPO_S_PER_REP, tempo, text)


def poor_data_quality(doc: dict, day: str) -> SuggestionDraft | None:
    """Fires when the analysis found the data unreliable (quality.ok false); says what to change at the camera."""
    quality = _quality(doc)
    if quality.get("ok") is not False:
        return None
    what = exercise_plural(doc.get("exercise"))
    tracked = _number(quality, "tracked_fraction", "doc['quality']")
    outliers = _number(quality, "outlier_fraction", "doc['quality']")
    if tracked is not None and tracked < QUALITY_MIN_TRACKED_FRACTION:
        text = (
            f"{_sentence(day)} the camera could not see all of you during your {what} (it saw you {tracked:.0%} "
            "of the time). Please step into view: stand so that you see your whole body, from head to feet, "
            "on the screen."
        )
        return SuggestionDraft(
            POOR_DATA_QUALITY, "quality.tracked_fraction", "<", QUALITY_MIN_TRACKED_FRACTION, tracked, text
        )
    if outliers is not None and outliers > QUALITY_MAX_OUTLIER_FRACTION:
        text = (
            f"{_sentence(day)} the camera had trouble following your {what}. Please make sure the room is well lit, "
            "nothing stands between you and the camera, and the camera points straight at you."
        )
        return SuggestionDraft(
            POOR_DATA_QUALITY, "quality.outlier_fraction", ">", QUALITY_MAX_OUTLIER_FRACTION, outliers, text
        )
    text = (
        f"{_sentence(day)} the camera could not measure your {what} well. Please move the camera so that it faces you "
        "and sees your whole body, then try again."
    )
    return SuggestionDraft(POOR_DATA_QUALITY, "quality.ok", "==", 0.0, 0.0, text)


def missed_days(
    history: list[tuple[dt.datetime, dict]], expected_per_week: int | None, now: dt.datetime, exercise: object = None
) -> SuggestionDraft | None:
    """Fires when fewer of the last 7 days (today included, UTC) had a session than the plan expects per week.

    Only judged once the patient has sessions from before that week (a first week is never "missed").
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
    day_word = "day" if active == 1 else "days"
    what = exercise_plural(exercise)
    what = "this exercise" if what == "repetitions" else what
    text = (
        f"In the 7 days up to {now:%A} {now.day} {now:%B} you did {what} on {active} {day_word}. Your plan asks "
        f"for {expected} days a week. Try to choose a fixed time of day for your exercises."
    )
    return SuggestionDraft(MISSED_DAYS, "active_days_last_7d", "<", float(expected), float(active), text)


def evaluate(
    doc: dict,
    *,
    prescribed_reps: int | None,
    history: list[tuple[dt.datetime, dict]],
    expected_per_week: int | None,
    now: dt.datetime,
    today: dt.date | None = None,
) -> list[SuggestionDraft]:
    """Returns the drafts of every rule that fires for one analysed session.

    doc: the analysis document of the session (backend.analysis.report). prescribed_reps: repetitions per set of
    the plan, None = no plan. history: (started_at, document) of earlier sessions of the same patient and exercise.
    expected_per_week: sessions per week of the plan. now: when the session happened (timezone-aware). today: the
    day the advice is written (UTC), which decides whether the text names the session's weekday or its date;
    defaults to the day of now.
    When quality.ok is false only the data-quality and missed-days rules run: the measurements are not trusted.
    Raises ValueError naming the argument or document key that is malformed.
    """
    if not isinstance(doc, dict):
        raise ValueError(f"doc must be a dict (the analysis document), got {type(doc).__name__}")
    now = _aware(now, "now")
    prescribed_reps = _positive_int(prescribed_reps, "prescribed_reps")
    expected_per_week = _positive_int(expected_per_week, "expected_per_week")
    past = _checked_history(history)
    if today is not None and (not isinstance(today, dt.date) or isinstance(today, dt.datetime)):
        raise ValueError(f"today must be a date or None, got {today!r}")
    day = session_day(now, now.date() if today is None else today)
    if _quality_ok(doc):
        drafts = [fewer_reps(doc, prescribed_reps, day), rom_drop(doc, past, now, day), too_fast(doc, day)]
    else:
        drafts = [poor_data_quality(doc, day)]
    drafts.append(missed_days(past, expected_per_week, now, doc.get("exercise")))
    return [d for d in drafts if d is not None]
