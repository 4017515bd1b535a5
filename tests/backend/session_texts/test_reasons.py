"""The analysis' reasons (backend.session_texts.reasons): stored as a message id and its numbers, written in the
reader's language from them with the locale's numbers; a text an older analysis stored (matching no message) stays as
stored."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from backend.i18n import Translator, translator
from backend.session_texts import reasons
from kinect_agent.analysis import balance, intervals, quality
from kinect_agent.analysis import reasons as why
from kinect_agent.analysis.document import reason_of_text
from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.analysis.reasons import Reason, UnknownReason
from kinect_agent.analysis.report import analyze_recording
from kinect_agent.recording import Recording
from kinect_agent.sources.simulator import simulate_truth
from tests.kinect_agent.analysis.test_document import ENGLISH

LOCALES = ("de", "es", "fr")
# one reason per message, read from the English text an older document stored
STORED = {text: Reason.model_validate(reason_of_text(text)) for text in ENGLISH}


@pytest.mark.parametrize("locale", LOCALES)
def test_every_reason_is_written_in_every_language(locale):
    t = translator(locale)
    written = {text: reasons.written(r, t) for text, r in STORED.items()}
    assert all(written[text] != text for text in ENGLISH), [w for text, w in written.items() if w == text]
    assert len(set(written.values())) == len(written), "each reason says something of its own"
    assert all(
        r.id is not None and written[text] == t.gettext(why.BY_ID[r.id].message)
        for text, r in STORED.items()
        if not r.params
    )
    too_short = written["only 1.2 s recorded (at least 3 s needed)"]
    assert "1,2 s" in too_short, f"the locale's decimal comma: {too_short}"
    tracked = written["the body was tracked in 46% of the samples (at least 60% needed)"]
    assert "46" in tracked and "60" in tracked, tracked


def test_numbers_follow_the_locale():
    assert reasons.written(why.TOO_LITTLE_TRACKED.reason(tracked=0.456, needed=0.6), translator("fr")) == (
        "le corps a été suivi dans 46\u00a0% des mesures (il en faut au moins 60\u00a0%)")  # fmt: skip
    assert reasons.written(why.TOO_UNCERTAIN.reason(width=74.4, most=60), translator("de")) == (
        "die Erfassung ist zu unsicher: ein 95-%-Intervall wäre 74° breit (gezeigt werden höchstens 60°)")  # fmt: skip
    assert "2,5 s" in reasons.written(why.NEVER_STILL.reason(seconds=2.5), translator("fr"))


@pytest.mark.parametrize("therapist", [False, True])
def test_english_is_written_from_the_ids_as_the_older_documents_stored_it(therapist):
    t = Translator("en", therapist=therapist)
    assert {text: reasons.written(r, t) for text, r in STORED.items()} == {text: text for text in ENGLISH}


def test_a_stored_text_stays_as_stored_in_every_language():
    older = Reason.model_validate(reason_of_text("an older analysis wrote this"))
    assert older.id is None
    assert {reasons.written(older, translator(locale)) for locale in (*LOCALES, "en")} == {older.text}


def test_an_unknown_id_fails_by_name():
    with pytest.raises(ValidationError, match="unknown reason id 'too_blurry'"):
        Reason(id="too_blurry")
    unchecked = Reason.model_construct(id="too_blurry", params={}, text=None)
    with pytest.raises(UnknownReason, match="too_blurry"):
        reasons.written(unchecked, translator("de"))


def test_the_analysis_stores_ids_and_numbers():
    rng = np.random.default_rng(3)
    x = np.where(rng.random(200) < 0.3, rng.normal(40, 5, 200), np.nan)
    said = intervals.withheld_reason("knee_flexion_L", x, None)
    assert said is not None and said.id == "out_of_plane" and 0.2 < float(said.params["defined"]) < 0.4, said
    wide = intervals.withheld_reason("knee_flexion_L", np.full(50, 30.0), {"min_deg": [0.0, 80.0]})
    assert wide == Reason(id="too_uncertain", params={"width": 80.0, "most": intervals.MAX_WIDTH_DEG})
    assert intervals.withheld_reason("shoulder_rotation_L", x, None) == Reason(id="rotation_undefined")
    assert balance.missing_reason(np.zeros(1), np.zeros((1, 20, 3)), {}) == Reason(id="recording_too_short")
    assert quality.MIN_FRAMES > 0 and why.TOO_FEW_FRAMES.reason(frames=12, needed=30).params == {
        "frames": 12, "needed": 30}  # fmt: skip


def test_a_reason_refuses_missing_or_extra_numbers():
    with pytest.raises(ValidationError, match="needs the numbers"):
        why.TOO_FEW_FRAMES.reason(frames=3)
    with pytest.raises(ValidationError, match="needs the numbers"):
        why.GAPS.reason(frames=3)


# one basis per message, with values as kinect_agent.analysis.indicators writes them
BASES = [why.BASIS_FLEXIBILITY.basis(angle="hip_abduction_L", low=0, high=45),
         why.BASIS_FLEXIBILITY_NO_ANGLE.basis(low=0, high=45), why.BASIS_ENDURANCE_TARGET.basis(target=12),
         why.BASIS_ENDURANCE_USUAL.basis(usual=8.5), why.BASIS_ENDURANCE_NONE.basis(),
         why.BASIS_STRENGTH_RISE.basis(fast=0.5, slow=2), why.BASIS_STRENGTH_SPEED.basis(),
         why.BASIS_STRENGTH_SPEED_NONE.basis(), why.BASIS_BALANCE_SWAY.basis(good=1, poor=6)]  # fmt: skip


@pytest.mark.parametrize("locale", LOCALES)
def test_every_basis_is_written_in_every_language_with_the_angle_in_words(locale):
    assert {b.id for b in BASES} == set(why.BASES_BY_ID), "one example per message"
    t, english = translator(locale), [reasons.written(b, translator("en")) for b in BASES]
    written = [reasons.written(b, t) for b in BASES]
    assert not set(written) & set(english) and len(set(written)) == len(written), written
    assert "hip_abduction_L" not in written[0] and "left hip abduction" in english[0], (english[0], written[0])
    assert "8,5" in written[3], written[3]
    assert "0,5 s" in written[5], written[5]


def test_a_withheld_range_is_written_in_the_readers_language():
    raw = simulate_truth("elbow_flexion", 3, seed=2, amplitude_deg=60.0)
    moved = simulate_truth("elbow_flexion", 3, seed=2, amplitude_deg=100.0)
    doc = analyze_recording(raw, EXERCISES["elbow_flexion"], filtered=Recording(raw.t, moved.positions, raw.state,
                                                                                raw.meta))  # fmt: skip
    english = reasons.with_texts(doc, translator("en")).range_of_motion_withheld
    german = reasons.with_texts(doc, translator("de")).range_of_motion_withheld
    assert english and german and set(english) == set(german) == {"elbow_flexion_L", "elbow_flexion_R"}, english
    left_en, left_de = english["elbow_flexion_L"], german["elbow_flexion_L"]
    assert left_en.text and "beyond what the camera measured" in left_en.text, left_en
    assert left_de.text and left_de.text != left_en.text and left_de.id == "beyond_raw", left_de


def test_withheld_repetitions_and_their_median_are_written_in_the_readers_language():
    """An elbow bent 165° from its rest of 8° passes what an elbow bends (170°): the repetitions' numbers and the
    median amplitude are withheld, and why is written in the reader's words."""
    doc = analyze_recording(simulate_truth("elbow_flexion", 3, seed=2, amplitude_deg=165.0), EXERCISES["elbow_flexion"])
    assert doc.rom_deg is None and all(r.peak_deg is None for r in doc.repetition_list), doc.repetition_list
    english, german = reasons.with_texts(doc, translator("en")), reasons.with_texts(doc, translator("de"))
    first_en, first_de = english.repetition_list[0].withheld, german.repetition_list[0].withheld
    assert first_en and first_en.text and "more than the joint can bend (170°)" in first_en.text, first_en
    assert first_de and first_de.text and "mehr als das Gelenk beugen kann" in first_de.text, first_de
    rom_en, rom_de = english.rom_deg_withheld, german.rom_deg_withheld
    assert rom_en and rom_en.text and rom_en.text.startswith("in 3 of 3 repetitions the curve reaches"), rom_en
    assert rom_de and rom_de.text and rom_de.text.startswith("in 3 von 3 Wiederholungen"), rom_de
