"""Advice written by the rules is stored as what the rule found and written in the reader's language when read: a
suggestion made while the patient read English is German once the patient changes to German (API, replies, the
data archive), English in the therapist's PDF report; a therapist's text stays as written."""

from __future__ import annotations

import datetime as dt
import io
import json
import subprocess
import zipfile
from typing import Any

import pytest

from backend.database import utcnow
from backend.i18n import LOCALES, translator
from backend.suggestions import rules
from backend.suggestions.models import Suggestion
from backend.suggestions.rules import AdviceParams, advice_text, evaluate
from kinect_agent.analysis.document import AnalysisReport
from tests.backend.session_rows import report

NOW = dt.datetime(2026, 11, 23, 10, 0, tzinfo=dt.UTC)


def _pain_advice(client, db_session, patient, therapist, auth_headers, exercise, store, pain=8) -> Suggestion:
    """Returns the approved pain_high advice made when the patient said `pain` after a set, in their language."""
    session = store(patient, exercise, utcnow() - dt.timedelta(hours=1))
    r = client.put(f"/api/v1/sessions/{session.id}/feeling", json={"pain": pain, "effort": 3}, headers=auth_headers(
        patient))  # fmt: skip
    assert r.status_code == 200, r.text
    row = db_session.query(Suggestion).filter_by(patient_id=patient.id, rule="pain_high").one()
    r = client.post(f"/api/v1/suggestions/{row.id}/approve", headers=auth_headers(therapist))
    assert r.status_code == 200, r.text
    return row


def _set_locale(client, patient, therapist, auth_headers, locale) -> None:
    r = client.patch(f"/api/v1/patients/{patient.id}", json={"locale": locale}, headers=auth_headers(therapist))
    assert r.status_code == 200 and r.json()["locale"] == locale, r.text


def _advice(client, patient, headers) -> list[dict[str, Any]]:
    r = client.get(f"/api/v1/patients/{patient.id}/suggestions", headers=headers)
    assert r.status_code == 200, r.text
    return r.json()["items"]


def test_advice_made_in_english_is_german_after_the_patient_changes_language(
    client, db_session, make_patient_with_therapist, auth_headers, exercise, store
):
    patient, therapist = make_patient_with_therapist()
    row = _pain_advice(client, db_session, patient, therapist, auth_headers, exercise, store)
    assert "your pain was 8 of 10" in row.text, row.text  # written in English: the patient had no language yet
    (before,) = _advice(client, patient, auth_headers(patient))
    assert before["text"] == row.text and before["locale"] == "en"
    _set_locale(client, patient, therapist, auth_headers, "de")
    (after,) = _advice(client, patient, auth_headers(patient))
    assert after["locale"] == "de" and "Schmerzen von 8 von 10" in after["text"], after["text"]
    assert after["text"] == advice_text("pain_high", "pain_nrs", AdviceParams.model_validate(row.params),
                                        translator("de"))  # fmt: skip
    device = client.get(f"/api/v1/sessions/{row.session_id}", headers=auth_headers(patient)).json()
    assert [s["text"] for s in device["suggestions"]] == [after["text"]], "the session's advice differs"


def test_accept_language_names_the_readers_language(
    client, db_session, make_patient_with_therapist, auth_headers, exercise, store
):
    patient, therapist = make_patient_with_therapist()
    _set_locale(client, patient, therapist, auth_headers, "de")
    _pain_advice(client, db_session, patient, therapist, auth_headers, exercise, store)
    (german,) = _advice(client, patient, auth_headers(therapist))
    assert german["locale"] == "de", "without Accept-Language: the patient's language"
    (english,) = _advice(client, patient, {**auth_headers(therapist), "Accept-Language": "en-GB,en;q=0.8"})
    assert english["locale"] == "en" and "your pain was 8 of 10" in english["text"], english
    (french,) = _advice(client, patient, {**auth_headers(therapist), "Accept-Language": "fr-CA"})
    assert french["locale"] == "fr" and french["text"] not in (german["text"], english["text"]), french
    (unknown,) = _advice(client, patient, {**auth_headers(therapist), "Accept-Language": "ja"})
    assert unknown["locale"] == "de", "a language the catalogues lack: the patient's"


def test_a_therapists_text_stays_as_written(client, make_patient_with_therapist, auth_headers):
    patient, therapist = make_patient_with_therapist()
    r = client.post(f"/api/v1/patients/{patient.id}/suggestions", json={"text": "Hold the top for two seconds."},
                    headers=auth_headers(therapist))  # fmt: skip
    assert r.status_code == 201 and r.json()["locale"] is None, r.text
    _set_locale(client, patient, therapist, auth_headers, "es")
    (shown,) = _advice(client, patient, {**auth_headers(patient), "Accept-Language": "es"})
    assert shown["text"] == "Hold the top for two seconds." and shown["locale"] is None


def test_a_row_without_params_keeps_its_text(client, db_session, make_patient_with_therapist, auth_headers):
    patient, therapist = make_patient_with_therapist()
    db_session.add(Suggestion(patient_id=patient.id, source="system", rule="fewer_reps", metric="repetitions",
                              comparison="<", threshold=10.0, value=6.0, text="Am Montag 6 von 10.",
                              status="approved"))  # fmt: skip
    db_session.flush()
    (shown,) = _advice(client, patient, {**auth_headers(patient), "Accept-Language": "en"})
    assert shown["text"] == "Am Montag 6 von 10." and shown["locale"] is None


def test_the_reply_shows_the_advice_in_the_readers_language(
    client, db_session, make_patient_with_therapist, auth_headers, exercise, store
):
    patient, therapist = make_patient_with_therapist()
    row = _pain_advice(client, db_session, patient, therapist, auth_headers, exercise, store)
    _set_locale(client, patient, therapist, auth_headers, "de")
    r = client.post(f"/api/v1/patients/{patient.id}/replies", json={"suggestion_id": row.id, "preset": "done"},
                    headers=auth_headers(patient))  # fmt: skip
    assert r.status_code == 201 and "Schmerzen von 8 von 10" in r.json()["suggestion_text"], r.text
    r = client.get("/api/v1/replies", headers={**auth_headers(therapist), "Accept-Language": "en"})
    assert "your pain was 8 of 10" in r.json()["items"][0]["suggestion_text"], r.text


def test_the_archive_has_the_advice_in_the_patients_language_now(
    fetch_archive, client, db_session, make_patient_with_therapist, auth_headers, exercise, store
):
    patient, therapist = make_patient_with_therapist()
    row = _pain_advice(client, db_session, patient, therapist, auth_headers, exercise, store)
    _set_locale(client, patient, therapist, auth_headers, "fr")
    response = fetch_archive(patient.id, auth_headers(patient))
    assert response.status_code == 200, response.text
    (advice,) = json.loads(zipfile.ZipFile(io.BytesIO(response.content)).read("advice.json"))
    assert advice["locale"] == "fr" and advice["text_as_first_written"] == row.text, advice
    assert advice["text"] == advice_text("pain_high", "pain_nrs", AdviceParams.model_validate(row.params),
                                         translator("fr"))  # fmt: skip
    assert advice["params"]["pain"] == 8 and advice["params"]["version"] == 1


def test_the_report_has_approved_advice_in_english(
    client, db_session, make_patient_with_therapist, auth_headers, exercise, store, tmp_path
):
    patient, therapist = make_patient_with_therapist()
    _set_locale(client, patient, therapist, auth_headers, "de")
    row = _pain_advice(client, db_session, patient, therapist, auth_headers, exercise, store)
    assert "Schmerzen von 8 von 10" in row.text
    today = dt.datetime.now(dt.UTC).date()
    response = client.get(f"/api/v1/patients/{patient.id}/report.pdf", headers=auth_headers(therapist),
                          params={"from": str(today - dt.timedelta(days=7)), "to": str(today)})  # fmt: skip
    assert response.status_code == 200, response.text
    (tmp_path / "r.pdf").write_bytes(response.content)
    text = subprocess.run(["pdftotext", str(tmp_path / "r.pdf"), "-"], capture_output=True, text=True,
                          check=True).stdout  # fmt: skip
    assert "Advice from the rules, approved" in text and "your pain was 8 of 10" in " ".join(text.split()), text


def _doc(**overrides) -> AnalysisReport:
    good = {"exercise": "squat", "repetitions": 10, "rom_deg": 90.0, "tempo_s_per_rep": 3.0,
            "quality": {"ok": True, "tracked_fraction": 0.99, "outlier_fraction": 0.01}}  # fmt: skip
    return report(**(good | overrides))


CASES = {  # one document per text of every session rule: (doc, prescribed_reps, history days ago, per week, today)
    "fewer_reps": (_doc(repetitions=6), 10, (), None, None),
    "fewer_reps none": (_doc(repetitions=0), 8, (), None, dt.date(2026, 12, 10)),
    "rom_drop": (_doc(rom_deg=60.0), None, (1, 8, 15, 20), None, None),
    "too_fast": (_doc(tempo_s_per_rep=1.2), None, (), None, None),
    "tracked": (_doc(quality={"ok": False, "tracked_fraction": 0.62}), None, (), None, None),
    "outliers": (_doc(quality={"ok": False, "tracked_fraction": 0.99, "outlier_fraction": 0.2}), None, (), None,
                 None),
    "quality": (_doc(quality={"ok": False}), None, (), None, None),
    "missed_days": (_doc(), None, (9, 10), 4, None),
    "missed_days unknown exercise": (_doc(exercise="juggling"), None, (9, 10), 4, None),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("written_in", LOCALES)
def test_what_a_rule_found_writes_its_advice_in_every_language(case, written_in):
    doc, reps, days, per_week, today = CASES[case]
    history: list[tuple[dt.datetime, AnalysisReport | None]] = [(NOW - dt.timedelta(days=d), _doc()) for d in days]

    def written(locale: str) -> list[rules.SuggestionDraft]:
        return evaluate(doc, t=translator(locale), prescribed_reps=reps, history=history, expected_per_week=per_week,
                        now=NOW, today=today)  # fmt: skip

    drafts = written(written_in)
    assert drafts, case
    for locale in LOCALES:
        direct = {d.rule: d.text for d in written(locale)}
        for draft in drafts:
            stored = AdviceParams.model_validate(draft.params.model_dump(mode="json"))  # as the database keeps it
            assert advice_text(draft.rule, draft.metric, stored, translator(locale)) == direct[draft.rule], (
                case, written_in, locale)  # fmt: skip


@pytest.mark.parametrize("locale", LOCALES)
def test_the_pain_rules_write_their_advice_in_every_language(locale):
    t = translator(locale)
    day = rules.SessionDay.of(NOW, NOW.date())
    high = rules.pain_high(7, 5, "squat", day, translator("en"))
    rising = rules.pain_rising([(NOW - dt.timedelta(days=d), p) for d, p in ((20, 2), (10, 3), (1, 6))], NOW,
                               translator("en"))  # fmt: skip
    assert high is not None and rising is not None
    high_again = rules.pain_high(7, 5, "squat", day, t)
    assert high_again is not None and advice_text(high.rule, high.metric, high.params, t) == high_again.text
    again = rules.pain_rising([(NOW - dt.timedelta(days=d), p) for d, p in ((20, 2), (10, 3), (1, 6))], NOW, t)
    assert again is not None and advice_text(rising.rule, rising.metric, rising.params, t) == again.text
