"""The texts the server writes for the session page and the replay page, in the reader's language (issue 23, point
2): camera advice (patient-facing, `messages`, de/es/fr), data-quality labels and notes (therapist pages,
`therapist`), the states of what a worker prepares; codes and params stay the same in every language."""

from __future__ import annotations

import pytest

import backend.i18n as i18n
from backend.analysis import data_quality
from backend.analysis.camera_advice import advice_text
from backend.i18n import Translator, translator
from backend.i18n.catalogues import marks_in_template_literals
from backend.sessions import detail
from kinect_agent.analysis.validity import REASONS
from tests.backend.khs_files import make_khs_at_distance
from tests.catalogue_copies import copy_with_therapist_catalogues

SEEDS = (1, 2)


def _detail(client, session_id: int, headers: dict) -> dict:
    response = client.get(f"/api/v1/sessions/{session_id}/detail", headers=headers)
    assert response.status_code == 200, response.text
    return response.json()


@pytest.mark.parametrize("seed", SEEDS)
def test_a_patient_reads_the_camera_advice_in_their_language_with_the_same_code_and_params(
    client, db_session, upload, auth_headers, seed
):
    session_id, patient, _ = upload(make_khs_at_distance(seed=seed), "squat")
    headers = auth_headers(patient)
    english = _detail(client, session_id, headers)["quality"]["advice"]
    assert english[0]["code"] == "too_close", english  # (and feet_cut_off: at 1.1 m the feet leave the picture)
    assert english[0]["params"]["distance_m"] == pytest.approx(1.1, abs=0.05)
    assert english[0]["text"].startswith("You were about 1.1 m from the camera"), english[0]["text"]

    patient.locale = "de"  # chosen by the patient (or set by the therapist)
    db_session.flush()
    german = _detail(client, session_id, headers)["quality"]["advice"]
    assert [(a["code"], a["params"]) for a in german] == [(a["code"], a["params"]) for a in english]
    assert german[0]["text"].startswith("Sie waren etwa 1,1 m von der Kamera entfernt"), german[0]["text"]

    spanish = _detail(client, session_id, headers | {"Accept-Language": "es"})["quality"]["advice"]
    assert spanish[0]["text"].startswith("Estaba a unos 1,1 m de la cámara"), "the page's language wins"


def test_the_therapist_reads_english_while_the_therapist_pages_have_no_german_catalogue(client, upload, auth_headers):
    session_id, _, therapist = upload(make_khs_at_distance(seed=1), "squat")
    body = _detail(client, session_id, auth_headers(therapist) | {"Accept-Language": "de"})
    assert [p["label"] for p in body["quality"]["parts"]] == [
        "Body seen by the camera", "Tracking errors", "Steadiness of measured bone lengths"]  # fmt: skip
    assert body["uncertainty_note"] in (detail.UNCERTAINTY_NOTE, detail.NO_UNCERTAINTY_NOTE)
    assert body["quality"]["advice"][0]["text"].startswith("You were about 1.1 m")


@pytest.fixture
def german_therapist_catalogue(tmp_path, monkeypatch):
    """The shipped catalogues plus a German therapist.po translating the session page's server texts; the
    catalogue caches emptied before and after."""
    words = {"Body seen by the camera": "Vom Körper gesehen", "Tracking errors": "Messfehler",
             "Steadiness of measured bone lengths": "Stetigkeit der gemessenen Knochenlängen",
             detail.UNCERTAINTY_NOTE: "95-%-Intervalle aus den Winkel-SDs je Bild",
             detail.NO_UNCERTAINTY_NOTE: "Ohne Intervalle: die Datei speichert keine Unsicherheit."}  # fmt: skip
    locale_dir = copy_with_therapist_catalogues(tmp_path, {"de": words})
    i18n.forget_catalogues()
    monkeypatch.setattr(i18n, "LOCALE_DIR", locale_dir)
    yield words
    monkeypatch.undo()
    i18n.forget_catalogues()


def test_a_german_therapist_catalogue_writes_the_session_texts_in_german(
    client, upload, auth_headers, german_therapist_catalogue
):
    words = german_therapist_catalogue
    session_id, _, therapist = upload(make_khs_at_distance(seed=2), "squat")
    body = _detail(client, session_id, auth_headers(therapist) | {"Accept-Language": "de-AT,de;q=0.9"})
    assert [p["label"] for p in body["quality"]["parts"]] == [
        "Vom Körper gesehen", "Messfehler", "Stetigkeit der gemessenen Knochenlängen"]  # fmt: skip
    assert [p["name"] for p in body["quality"]["parts"]] == list(data_quality.PARTS), "the codes stay"
    assert body["uncertainty_note"] in (words[detail.UNCERTAINTY_NOTE], words[detail.NO_UNCERTAINTY_NOTE])
    advice = body["quality"]["advice"][0]
    assert advice["code"] == "too_close" and advice["text"].startswith("Sie waren etwa 1,1 m"), "messages' German"


def test_the_device_limits_shown_are_the_agents_reasons_marked_for_translation():
    agents = {REASONS["out_of_plane"].format(want=w) for w in ("side", "front")} | {
        REASONS[k] for k in ("transverse", "unknown_view", "metric_scale")}  # fmt: skip
    assert set(detail.VALIDITY_REASONS) == agents, "kinect_agent's REASONS changed: mark the new words in detail.py"


@pytest.mark.parametrize("locale", ["de", "es", "fr"])
def test_every_piece_of_advice_is_written_in_every_language(locale):
    t = translator(locale)
    cases = [("too_close", {"distance_m": 1.21}), ("too_far", {"distance_m": 4.46}),
             ("off_centre", {"distance_m": 0.95}), ("feet_cut_off", {})]  # fmt: skip
    cases += [(f"{limb}_out_of_view", {"sides": s, "fraction": 0.354}) for limb in ("hand", "foot")
              for s in ("left", "right", "both")]  # fmt: skip
    texts = [advice_text(code, params, t) for code, params in cases]
    english = [advice_text(code, params, Translator("en")) for code, params in cases]
    assert all(a != b for a, b in zip(texts, english, strict=True)), "each is translated"
    assert len(set(texts)) == len(texts), "each case says something of its own"
    assert "1,2 m" in texts[0] and "4,5 m" in texts[1], "the locale's decimal comma"
    assert all("35" in text and "%" in text for text in texts[4:]), texts[4:]


def test_the_replay_state_is_said_in_the_patients_language(client, db_session, upload, auth_headers):
    session_id, patient, _ = upload(make_khs_at_distance(seed=1, z_m=2.5), "squat")
    patient.locale = "fr"
    db_session.flush()
    state = client.get(f"/api/v1/sessions/{session_id}/replay/state", headers=auth_headers(patient))
    assert state.status_code == 200, state.text
    said = "La relecture est en file d’attente ; elle sera créée dans un instant."
    assert state.json() == {"state": "preparing", "detail": said}


def test_the_check_finds_a_mark_babel_does_not_extract():
    source = 'say(`${I18n.t("Being prepared.")} ${d.detail}`);\nsay(I18n.t("Fine.") + " " + d.detail);\n'
    problems = marks_in_template_literals("frontend/static/x.js", source)
    assert [p.where for p in problems] == ["frontend/static/x.js:1"], problems
