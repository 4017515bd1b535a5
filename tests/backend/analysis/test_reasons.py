"""The analysis' reasons (backend.analysis.reasons): stored in English in the metrics document, written in the
reader's language when read, with the locale's numbers; a text of an older analysis stays as stored."""

from __future__ import annotations

import numpy as np
import pytest

from backend.analysis import balance, intervals, quality, reasons
from backend.i18n import Translator, translator

LOCALES = ("de", "es", "fr")
# one English text per reason, as the analysis writes it
ENGLISH = {
    reasons.TOO_FEW_FRAMES: "only 12 frames (at least 30 needed)",
    reasons.TOO_SHORT: "only 1.2 s recorded (at least 3 s needed)",
    reasons.TOO_LITTLE_TRACKED: "the body was tracked in 46% of the samples (at least 60% needed)",
    reasons.TOO_MANY_ERRORS: "35% of the samples were tracking errors (at most 20% allowed)",
    reasons.GAPS: "the measured positions have gaps",
    reasons.ROTATION_UNDEFINED: "shoulder rotation is undefined while the elbow is straight, so it has no interval",
    reasons.OUT_OF_PLANE: "the angle is defined in only 41% of the frames (the limb was out of its plane)",
    reasons.JOINTS_UNTRACKED: "the joints of this angle were tracked in only 52% of the frames",
    reasons.UNKNOWN_ANGLE: "the angle or its uncertainty is unknown in every frame, or it spun through a full turn",
    reasons.TOO_UNCERTAIN: "the tracking is too uncertain: a 95 % interval would span 74° (at most 60° is shown)",
    reasons.RECORDING_TOO_SHORT: "the recording is too short",
    reasons.NOT_STANDING: "the patient was seated or crouching: balance is measured while standing",
    reasons.NEVER_STILL: "the patient never stood still with both feet down for 2 s in total (steps, a raised leg or "
    "a bent trunk do not count)",
}


def test_every_reason_has_an_english_example():
    assert set(ENGLISH) == set(reasons.REASONS)


@pytest.mark.parametrize("locale", LOCALES)
def test_every_reason_is_written_in_every_language(locale):
    t = translator(locale)
    written = {r: reasons.in_language(text, t) for r, text in ENGLISH.items()}
    assert all(written[r] != ENGLISH[r] for r in ENGLISH), [w for r, w in written.items() if w == ENGLISH[r]]
    assert len(set(written.values())) == len(written), "each reason says something of its own"
    assert all(written[r] == t.gettext(r.message) for r in ENGLISH if not r.kinds)
    assert "1,2 s" in written[reasons.TOO_SHORT], "the locale's decimal comma"
    assert "46" in written[reasons.TOO_LITTLE_TRACKED] and "60" in written[reasons.TOO_LITTLE_TRACKED]


def test_numbers_follow_the_locale():
    fr = translator("fr")
    assert reasons.in_language(ENGLISH[reasons.TOO_LITTLE_TRACKED], fr) == (
        "le corps a été suivi dans 46\u00a0% des mesures (il en faut au moins 60\u00a0%)")  # fmt: skip
    assert reasons.in_language(ENGLISH[reasons.TOO_UNCERTAIN], translator("de")) == (
        "die Erfassung ist zu unsicher: ein 95-%-Intervall wäre 74° breit (gezeigt werden höchstens 60°)")  # fmt: skip


def test_english_and_unknown_texts_stay_as_stored():
    for text in ENGLISH.values():
        assert reasons.in_language(text, Translator("en")) == text
        assert reasons.in_language(text, Translator("en", therapist=True)) == text
    older = "an older analysis wrote this"
    assert reasons.in_language(older, translator("de")) == older


def test_the_analysis_writes_the_reasons_it_can_read_back():
    rng = np.random.default_rng(3)
    x = np.where(rng.random(200) < 0.3, rng.normal(40, 5, 200), np.nan)
    said = intervals.withheld_reason("knee_flexion_L", x, None)
    assert reasons.OUT_OF_PLANE.pattern.fullmatch(said), said
    assert reasons.TOO_UNCERTAIN.pattern.fullmatch(intervals.withheld_reason(
        "knee_flexion_L", np.full(50, 30.0), {"min_deg": [0.0, 80.0], "max_deg": [70.0, 75.0]}))  # fmt: skip
    assert reasons.ROTATION_UNDEFINED.english() == intervals.withheld_reason("shoulder_rotation_L", x, None)
    assert balance.missing_reason(np.zeros(1), np.zeros((1, 20, 3)), {}) == ENGLISH[reasons.RECORDING_TOO_SHORT]
    assert quality.MIN_FRAMES > 0 and reasons.TOO_FEW_FRAMES.english(frames=12, needed=30) == ENGLISH[
        reasons.TOO_FEW_FRAMES]  # fmt: skip


def test_a_reason_refuses_missing_or_extra_numbers():
    with pytest.raises(ValueError, match="needs"):
        reasons.TOO_FEW_FRAMES.english(frames=3)
