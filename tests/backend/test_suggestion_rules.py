"""Suggestion rules: each fires just past its threshold and stays silent at it."""

from __future__ import annotations

import datetime as dt
import re
from typing import Any

import pytest

from backend.suggestions import rules
from backend.suggestions.rules import SuggestionDraft, evaluate
from kinect_agent.analysis.document import AnalysisReport
from tests.backend.session_rows import report

NOW = dt.datetime(2026, 11, 23, 10, 0, tzinfo=dt.UTC)


def _doc(**overrides) -> AnalysisReport:
    """A good session: 10 repetitions, 90 degrees, 3 s per repetition, quality ok."""
    good = {
        "exercise": "squat",
        "repetitions": 10,
        "rom_deg": 90.0,
        "tempo_s_per_rep": 3.0,
        "quality": {"ok": True, "tracked_fraction": 0.99, "outlier_fraction": 0.01, "reasons": []},
    }
    return report(**(good | overrides))


def _past(days_ago: float, **overrides) -> tuple[dt.datetime, AnalysisReport]:
    return NOW - dt.timedelta(days=days_ago), _doc(**overrides)


def _eval(
    doc, *, prescribed_reps=None, history=(), expected_per_week=None, now=NOW, today=None
) -> dict[str, SuggestionDraft]:
    drafts = evaluate(
        doc,
        prescribed_reps=prescribed_reps,
        history=list(history),
        expected_per_week=expected_per_week,
        now=now,
        today=today,
    )
    by_rule = {d.rule: d for d in drafts}
    assert len(by_rule) == len(drafts), f"a rule fired twice: {drafts}"
    return by_rule


def test_good_session_fires_nothing():
    history = [_past(d) for d in (1, 3, 5, 8, 10, 12, 15, 17, 20)]
    assert _eval(_doc(), prescribed_reps=10, history=history, expected_per_week=3) == {}


# --- fewer repetitions than prescribed ---


def test_fewer_reps_fires_one_below_prescribed():
    draft = _eval(_doc(repetitions=9), prescribed_reps=10)[rules.FEWER_REPS]
    assert (draft.metric, draft.comparison, draft.threshold, draft.value) == ("repetitions", "<", 10.0, 9.0)
    assert draft.text.startswith("On Monday you did 9 of the 10 mini squats in your plan. Next time, try to do all 10.")
    assert draft.explanation == "repetitions 9 < 10"


def test_fewer_reps_names_the_exercise_and_the_weekday_of_the_session():
    saturday = NOW - dt.timedelta(days=2)
    doc = _doc(exercise="sit_to_stand", repetitions=6)
    draft = _eval(doc, prescribed_reps=10, now=saturday, today=NOW.date())[rules.FEWER_REPS]
    assert draft.text.startswith("On Saturday you did 6 of the 10 sit-to-stands in your plan.")


def test_fewer_reps_silent_at_prescribed():
    assert rules.FEWER_REPS not in _eval(_doc(repetitions=10), prescribed_reps=10)


def test_fewer_reps_silent_without_plan():
    assert rules.FEWER_REPS not in _eval(_doc(repetitions=1), prescribed_reps=None)


def test_fewer_reps_zero_says_none_counted():
    draft = _eval(_doc(repetitions=0), prescribed_reps=8)[rules.FEWER_REPS]
    assert draft.value == 0.0
    assert draft.text.startswith("On Monday the camera did not count any mini squats. Your plan asks for 8.")


# --- range of motion against the last weeks ---


def _rom_history(median: float = 80.0) -> list[Any]:
    return [_past(20, rom_deg=median - 10), _past(15, rom_deg=median), _past(6, rom_deg=median + 10)]


def test_rom_drop_fires_below_85_percent_of_median():
    draft = _eval(_doc(rom_deg=67.9), history=_rom_history(80.0))[rules.ROM_DROP]
    assert (draft.metric, draft.comparison, draft.value) == ("rom_deg", "<", 67.9)
    assert draft.threshold == pytest.approx(0.85 * 80.0)
    assert draft.text.startswith(
        "On Monday your mini squats were smaller movements than in the last weeks: 68 degrees, "
        "while it was about 80 degrees before."
    )


def test_rom_drop_silent_at_85_percent_of_median():
    assert rules.ROM_DROP not in _eval(_doc(rom_deg=68.0), history=_rom_history(80.0))


def test_rom_drop_needs_two_weeks_of_baseline():
    history = [_past(13.9, rom_deg=80.0), _past(10, rom_deg=80.0), _past(5, rom_deg=80.0)]
    assert rules.ROM_DROP not in _eval(_doc(rom_deg=10.0), history=history)


def test_rom_drop_needs_three_baseline_sessions():
    assert rules.ROM_DROP not in _eval(_doc(rom_deg=10.0), history=_rom_history()[:2])


def test_rom_drop_ignores_sessions_older_than_four_weeks_and_poor_quality():
    bad = {"ok": False, "tracked_fraction": 0.5, "outlier_fraction": 0.0, "reasons": [{"id": None, "text": "x"}]}
    history = [_past(40, rom_deg=200.0), _past(20, rom_deg=200.0, quality=bad), *_rom_history(80.0)]
    assert rules.ROM_DROP in _eval(_doc(rom_deg=67.9), history=history)
    assert rules.ROM_DROP not in _eval(_doc(rom_deg=68.0), history=history)


def test_rom_drop_is_not_written_from_a_withheld_range_of_motion():
    """A range of motion withheld (repetitions measured past what the joint bends: the camera lost the limb) is no
    number to compare: no rom_drop is written of it, and it is no baseline either."""
    why = {"id": "repetitions_beyond_anatomy", "params": {"withheld": 2, "count": 10, "reached": 177, "limit": 170}}
    assert rules.ROM_DROP not in _eval(_doc(rom_deg=None, rom_deg_withheld=why), history=_rom_history(80.0))
    withheld = [_past(d, rom_deg=None, rom_deg_withheld=why) for d in (20, 15, 6)]
    assert rules.ROM_DROP not in _eval(_doc(rom_deg=10.0), history=withheld)
    assert rules.ROM_DROP in _eval(_doc(rom_deg=10.0), history=_rom_history(80.0))  # the same with numbers fires


def test_rom_drop_ignores_other_exercises():
    history = [_past(d, rom_deg=80.0, exercise="shoulder_flexion") for d in (20, 15, 6)]
    assert rules.ROM_DROP not in _eval(_doc(rom_deg=10.0), history=history)


# --- too fast ---


def test_too_fast_fires_below_threshold():
    draft = _eval(_doc(tempo_s_per_rep=1.49))[rules.TOO_FAST]
    assert (draft.metric, draft.comparison, draft.threshold, draft.value) == (
        "tempo_s_per_rep",
        "<",
        rules.MIN_TEMPO_S_PER_REP,
        1.49,
    )
    assert draft.text.startswith("On Monday you did your mini squats quickly: about 1.5 seconds for each one.")
    assert "slow down" in draft.text


def test_too_fast_silent_at_threshold():
    assert rules.TOO_FAST not in _eval(_doc(tempo_s_per_rep=rules.MIN_TEMPO_S_PER_REP))


def test_too_fast_silent_without_tempo():
    assert rules.TOO_FAST not in _eval(_doc(tempo_s_per_rep=None, repetitions=0))


# --- data quality ---


def _quality(ok=False, tracked=0.99, outliers=0.0):
    return {
        "ok": ok,
        "tracked_fraction": tracked,
        "outlier_fraction": outliers,
        "reasons": [{"id": None, "text": "analysis reason"}],
    }


def test_poor_quality_low_tracking_asks_to_step_into_view():
    draft = _eval(_doc(quality=_quality(tracked=0.899)))[rules.POOR_DATA_QUALITY]
    assert (draft.metric, draft.comparison, draft.threshold, draft.value) == (
        "quality.tracked_fraction",
        "<",
        0.9,
        0.899,
    )
    assert draft.text.startswith("On Monday the camera could not see all of you during your mini squats")
    assert "step into view" in draft.text


def test_poor_quality_outliers_asks_to_fix_the_room():
    draft = _eval(_doc(quality=_quality(tracked=0.9, outliers=0.051)))[rules.POOR_DATA_QUALITY]
    assert (draft.metric, draft.comparison, draft.value) == ("quality.outlier_fraction", ">", 0.051)
    assert draft.text.startswith("On Monday the camera had trouble following your mini squats.")


def test_poor_quality_other_reason_asks_to_move_camera():
    draft = _eval(_doc(quality=_quality(tracked=0.9, outliers=0.05)))[rules.POOR_DATA_QUALITY]
    assert (draft.metric, draft.comparison, draft.threshold, draft.value) == ("quality.ok", "==", 0.0, 0.0)
    assert draft.text.startswith("On Monday the camera could not measure your mini squats well.")
    assert "move the camera" in draft.text


def test_good_quality_silent_even_with_low_fractions():
    assert rules.POOR_DATA_QUALITY not in _eval(_doc(quality=_quality(ok=True, tracked=0.1, outliers=0.9)))


def test_poor_quality_suppresses_measurement_rules():
    doc = _doc(quality=_quality(tracked=0.5), repetitions=1, tempo_s_per_rep=0.5, rom_deg=1.0)
    assert set(_eval(doc, prescribed_reps=10, history=_rom_history())) == {rules.POOR_DATA_QUALITY}


# --- missed days ---


def _sessions_on(days_ago: list[int]) -> list[Any]:
    return [_past(d) for d in days_ago]


def test_missed_days_fires_below_expected():
    history = _sessions_on([9, 3])  # with today: 2 active days in the last 7
    draft = _eval(_doc(), history=history, expected_per_week=3)[rules.MISSED_DAYS]
    assert (draft.metric, draft.comparison, draft.threshold, draft.value) == ("active_days_last_7d", "<", 3.0, 2.0)
    assert draft.text.startswith(
        "In the 7 days up to Monday 23 November you did mini squats on 2 days. Your plan asks for 3 days a week."
    )


def test_missed_days_silent_at_expected():
    assert rules.MISSED_DAYS not in _eval(_doc(), history=_sessions_on([9, 3, 6]), expected_per_week=3)


def test_missed_days_counts_days_not_sets():
    history = [_past(9), _past(0.1), _past(0.2)]  # three sets today
    assert rules.MISSED_DAYS in _eval(_doc(), history=history, expected_per_week=2)


def test_missed_days_window_is_seven_days_including_today():
    assert rules.MISSED_DAYS not in _eval(_doc(), history=_sessions_on([9, 6]), expected_per_week=2)
    assert rules.MISSED_DAYS in _eval(_doc(), history=_sessions_on([9, 7]), expected_per_week=2)


def test_missed_days_silent_in_the_first_week():
    assert rules.MISSED_DAYS not in _eval(_doc(), history=_sessions_on([6]), expected_per_week=5)
    assert rules.MISSED_DAYS not in _eval(_doc(), history=[], expected_per_week=5)


def test_missed_days_caps_expectation_at_seven():
    history = _sessions_on(list(range(0, 10)))
    assert rules.MISSED_DAYS not in _eval(_doc(), history=history, expected_per_week=14)


# --- sentences, not rule codes ---


@pytest.mark.parametrize(
    ("days_ago", "expected"),
    [
        (0, "on Monday"),
        (2, "on Saturday"),
        (6, "on Tuesday"),
        (7, "on 16 November"),
        (30, "on 24 October"),
        (330, "on 28 December 2025"),
    ],  # fmt: skip
)
def test_session_day_is_the_weekday_within_a_week_else_the_date(days_ago, expected):
    assert rules.session_day(NOW - dt.timedelta(days=days_ago), NOW.date()) == expected


def test_an_old_session_is_named_by_its_date():
    doc = _doc(exercise="deep_squat", repetitions=3)
    draft = _eval(doc, prescribed_reps=10, now=NOW - dt.timedelta(days=9), today=NOW.date())[rules.FEWER_REPS]
    assert draft.text.startswith("On 14 November you did 3 of the 10 deep squats in your plan.")


@pytest.mark.parametrize(
    ("slug", "plural"),
    [
        ("sit_to_stand", "sit-to-stands"),
        ("squat", "mini squats"),
        ("shoulder_abduction", "shoulder abductions"),
        ("no_such_exercise", "repetitions"),
        (None, "repetitions"),
    ],  # fmt: skip
)
def test_exercise_plural(slug, plural):
    assert rules.exercise_plural(slug) == plural


def test_every_text_is_plain_sentences_without_rule_codes():
    bad_quality = [_quality(tracked=0.5), _quality(tracked=0.95, outliers=0.2), _quality(tracked=0.95, outliers=0.0)]
    docs = [_doc(repetitions=4, rom_deg=40.0, tempo_s_per_rep=1.0), _doc(repetitions=0)]
    docs += [_doc(quality=q) for q in bad_quality]
    for doc in docs:
        fired = _eval(doc, prescribed_reps=10, history=[*_rom_history(), _past(9)], expected_per_week=5)
        assert fired
        for draft in fired.values():
            assert "mini squats" in draft.text and "Monday" in draft.text, draft.text
            for code in (draft.rule, draft.metric, "<", ">", "==", "_"):
                assert code not in draft.text, (code, draft.text)
            assert draft.text[0].isupper() and draft.text.endswith("."), draft.text


# --- bad input ---


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"doc": {"repetitions": 3}}, "doc must be an AnalysisReport"),
        ({"now": dt.datetime(2026, 11, 23)}, "now must be a timezone-aware datetime"),
        ({"prescribed_reps": 0}, "prescribed_reps must be a positive integer"),
        ({"expected_per_week": 2.5}, "expected_per_week must be a positive integer"),
        ({"history": [(NOW, {"rom_deg": 80.0})]}, "history[0] must be a (datetime, AnalysisReport or None) pair"),
        ({"history": [(dt.datetime(2026, 11, 1), None)]}, "history[0][0] must be a timezone-aware"),
        ({"today": NOW}, "today must be a date or None"),
    ],
)
def test_bad_input_names_what_and_where(kwargs, message):
    args = {"doc": _doc(), "prescribed_reps": 10, "history": [], "expected_per_week": 3, "now": NOW} | kwargs
    with pytest.raises(ValueError, match=re.escape(message)):
        evaluate(args.pop("doc"), **args)


def test_nan_metric_counts_as_missing():
    assert _eval(_doc(rom_deg=float("nan"), tempo_s_per_rep=float("nan")), history=_rom_history()) == {}


def test_a_session_whose_document_no_schema_reads_counts_as_a_day_but_not_in_the_baseline():
    unreadable = [(when, None) for when, _ in _rom_history(80.0)]
    assert rules.ROM_DROP not in _eval(_doc(rom_deg=10.0), history=unreadable)
    draft = _eval(_doc(), history=[_past(9), (NOW - dt.timedelta(days=3), None)], expected_per_week=3)
    assert draft[rules.MISSED_DAYS].value == 2.0  # 3 days ago and today
