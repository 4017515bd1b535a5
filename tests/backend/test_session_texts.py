"""The texts the server writes for the session page and the replay page, in the reader's language (issue 23, point
2): camera advice, data-quality labels and notes, the curves' labels, the analysis' reasons and why a session failed
(a patient reads them: `messages`, de/es/fr), the states of what a worker prepares; codes and params stay the same in
every language."""

from __future__ import annotations

from typing import Any

import pytest

import backend.i18n as i18n
from backend.i18n import Translator, translator
from backend.i18n.catalogues import marks_in_template_literals
from backend.session_texts import data_quality
from backend.session_texts.camera_advice import advice_text
from backend.sessions import detail
from kinect_agent.analysis.document import SCHEMA_VERSION
from kinect_agent.analysis.validity import REASONS
from tests.backend.khs_files import make_khs_at_distance, make_processed_khs
from tests.catalogue_copies import copy_with_therapist_catalogues

SEEDS = (1, 2)


def _detail(client, session_id: int, headers: dict[str, Any]) -> dict[str, Any]:
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
    """The shipped catalogues plus a German therapist.po (a heading of the session page: the therapist pages are in
    German from then on); the catalogue caches emptied before and after."""
    locale_dir = copy_with_therapist_catalogues(tmp_path, {"de": {"Data quality": "Datenqualität"}})
    i18n.forget_catalogues()
    monkeypatch.setattr(i18n, "LOCALE_DIR", locale_dir)
    yield
    monkeypatch.undo()
    i18n.forget_catalogues()


def test_a_german_therapist_catalogue_writes_the_session_texts_in_german(
    client, upload, auth_headers, german_therapist_catalogue
):
    session_id, _, therapist = upload(make_khs_at_distance(seed=2), "squat")
    body = _detail(client, session_id, auth_headers(therapist) | {"Accept-Language": "de-AT,de;q=0.9"})
    assert [p["label"] for p in body["quality"]["parts"]] == [
        "Von der Kamera gesehener Körper", "Erfassungsfehler",
        "Gleichmäßigkeit der gemessenen Knochenlängen"]  # fmt: skip
    assert [p["name"] for p in body["quality"]["parts"]] == list(data_quality.PARTS), "the codes stay"
    assert body["uncertainty_note"] in (translator("de").gettext(detail.UNCERTAINTY_NOTE),
                                        translator("de").gettext(detail.NO_UNCERTAINTY_NOTE))  # fmt: skip
    advice = body["quality"]["advice"][0]
    assert advice["code"] == "too_close" and advice["text"].startswith("Sie waren etwa 1,1 m"), "messages' German"
    assert body["curves"][0]["label"] == "Beugung des linken Knies, roh", body["curves"][0]["label"]


def test_the_device_limits_shown_are_the_agents_reasons_marked_for_translation():
    agents = {REASONS["out_of_plane"].format(want=w) for w in ("side", "front")} | {
        REASONS[k] for k in ("transverse", "unknown_view", "metric_scale")}  # fmt: skip
    assert set(detail.VALIDITY_REASONS) == agents, "kinect_agent's REASONS changed: mark the new words in detail.py"


@pytest.mark.parametrize("locale", ["de", "es", "fr"])
def test_every_piece_of_advice_is_written_in_every_language(locale):
    t = translator(locale)
    cases: list[tuple[str, dict[str, Any]]] = [("too_close", {"distance_m": 1.21}), ("too_far", {"distance_m": 4.46}),
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
    said = "La relecture est en file d’attente\u202f; elle sera créée dans un instant."
    assert state.json() == {"state": "preparing", "detail": said}


def test_the_check_finds_a_mark_babel_does_not_extract():
    source = 'say(`${I18n.t("Being prepared.")} ${d.detail}`);\nsay(I18n.t("Fine.") + " " + d.detail);\n'
    problems = marks_in_template_literals("frontend/static/x.js", source)
    assert [p.where for p in problems] == ["frontend/static/x.js:1"], problems


@pytest.mark.parametrize(("locale", "raw", "filtered"), [
    ("de", "Beugung des linken Knies, roh", "Beugung des linken Knies, gefiltert"),
    ("es", "flexión de la rodilla izquierda, sin filtrar", "flexión de la rodilla izquierda, filtrada"),
    ("fr", "flexion du genou gauche, brute", "flexion du genou gauche, filtrée"),
])  # fmt: skip
def test_a_patient_reads_the_curves_labels_in_their_language(
    client, db_session, upload, auth_headers, locale, raw, filtered
):
    session_id, patient, _ = upload(make_khs_at_distance(seed=1), "squat")
    english = _detail(client, session_id, auth_headers(patient))["curves"]
    assert [(c["angle"], c["kind"], c["label"]) for c in english[:2]] == [
        ("knee_flexion_L", "raw", "left knee flexion, raw"),
        ("knee_flexion_L", "filtered", "left knee flexion, filtered")]  # fmt: skip
    patient.locale = locale
    db_session.flush()
    curves = _detail(client, session_id, auth_headers(patient))["curves"]
    assert [c["label"] for c in curves[:2]] == [raw, filtered]
    assert (curves[0]["angle_label"], curves[1]["kind_label"]) == (raw.rpartition(",")[0], filtered.rpartition(" ")[2])
    assert [(c["angle"], c["kind"], c["deg"]) for c in curves] == [(c["angle"], c["kind"], c["deg"]) for c in english]


@pytest.mark.parametrize("locale", ["de", "es", "fr"])
def test_every_angle_has_words_in_every_language(locale):
    from backend.session_texts.session_detail import ANGLE_WORDS, angle_label
    from kinect_agent.body.angles import ANGLE_NAMES

    assert set(ANGLE_WORDS) == set(ANGLE_NAMES), "an angle without words"
    words = [angle_label(name, translator(locale)) for name in ANGLE_NAMES]
    assert len(set(words)) == len(words) and not set(words) & {angle_label(n) for n in ANGLE_NAMES}, words


def _english_document(document: dict[str, Any]) -> dict[str, Any]:
    """Returns a stored document as the server stored it before reason ids (schema 2, English texts): a failed
    quality check (one reason an analysis of before the catalogue wrote, matching no message), a withheld interval
    and balance not measured."""
    doc = dict(document) | {"schema_version": 2}
    doc["quality"] = doc["quality"] | {
        "ok": False,
        "reasons": ["the body was tracked in 46% of the samples (at least 60% needed)", OLDER_TEXT],
    }
    doc["range_of_motion_95_withheld"] = {"knee_flexion_L": "the joints of this angle were tracked in only 52% of the "
                                          "frames"}  # fmt: skip
    doc["balance"], doc["balance_missing"] = None, "the patient was seated or crouching: balance is measured while " \
        "standing"  # fmt: skip
    doc["indicators"] = doc["indicators"] | {"balance": doc["indicators"]["balance"] | {
        "missing": doc["balance_missing"], "value": None, "score": None}}  # fmt: skip
    return doc


OLDER_TEXT = "an analysis of 2026-11-20 wrote this"


def test_a_new_document_stores_its_reasons_as_ids_and_numbers_and_the_detail_writes_them(
    client, db_session, upload, auth_headers
):
    from sqlalchemy import select

    from backend.sessions.models import SessionMetric

    khs = make_processed_khs("seated_knee_extension", 3, seed=3)
    session_id, patient, _ = upload(khs, "seated_knee_extension")
    stored = db_session.scalar(select(SessionMetric.document).where(SessionMetric.session_id == session_id))
    assert stored["schema_version"] == SCHEMA_VERSION == 6
    not_standing: dict[str, Any] = {"id": "not_standing", "params": {}, "text": None}
    assert stored["balance_missing"] == stored["indicators"]["balance"]["missing"] == not_standing
    found = [*stored["quality"]["reasons"], *(stored["range_of_motion_95_withheld"] or {}).values()]
    assert all(set(r) == {"id", "params", "text"} and r["id"] and r["text"] is None for r in found), found
    patient.locale = "de"
    db_session.flush()
    body = _detail(client, session_id, auth_headers(patient))
    standing = "es wurde im Sitzen oder in der Hocke geübt: das Gleichgewicht wird im Stehen gemessen"
    assert body["balance_missing"] == standing
    assert body["balance_missing_reason"] == not_standing | {"text": standing}


def test_a_patient_reads_the_analysis_reasons_of_an_older_english_document_in_their_language(
    client, db_session, upload, auth_headers
):
    from sqlalchemy import select

    from backend.sessions.models import SessionMetric

    session_id, patient, therapist = upload(make_khs_at_distance(seed=1), "squat")
    metric = db_session.scalar(select(SessionMetric).where(SessionMetric.session_id == session_id))
    metric.document = doc = _english_document(metric.document)
    patient.locale = "de"
    db_session.flush()
    german = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(patient)).json()["metrics"]
    assert german["schema_version"] == SCHEMA_VERSION, "upgraded when read"
    assert german["quality"]["reasons"] == [
        {"id": "too_little_tracked", "params": {"tracked": 0.46, "needed": 0.6},
         "text": "der Körper wurde in 46\u00a0% der Messungen erfasst (mindestens 60\u00a0% nötig)"},
        {"id": None, "params": {}, "text": OLDER_TEXT},
    ]  # fmt: skip
    assert german["range_of_motion_95_withheld"] == {"knee_flexion_L": {
        "id": "joints_untracked", "params": {"tracked": 0.52},
        "text": "die Gelenke dieses Winkels wurden nur in 52\u00a0% der Bilder erfasst"}}  # fmt: skip
    standing = "es wurde im Sitzen oder in der Hocke geübt: das Gleichgewicht wird im Stehen gemessen"
    assert german["balance_missing"] == german["indicators"]["balance"]["missing"] == {
        "id": "not_standing", "params": {}, "text": standing}  # fmt: skip
    french = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(patient) | {"Accept-Language": "fr"})
    assert [r["text"] for r in french.json()["metrics"]["quality"]["reasons"]] == [
        "le corps a été suivi dans 46\u00a0% des mesures (il en faut au moins 60\u00a0%)", OLDER_TEXT]  # fmt: skip
    spanish = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(patient) | {"Accept-Language": "es"})
    assert spanish.json()["metrics"]["balance_missing"]["text"] == (
        "el ejercicio se hizo en posición sentada o agachada: el equilibrio se mide de pie")  # fmt: skip
    clinic = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(therapist)).json()["metrics"]
    assert [r["text"] for r in clinic["quality"]["reasons"]] == doc["quality"]["reasons"], "English, as it was stored"
    db_session.refresh(metric)
    assert metric.document == doc, "reading upgrades the answer, not the stored document"


def test_the_session_detail_says_the_analysis_reasons_in_the_readers_language():
    from kinect_agent.analysis import reasons as why

    gaps, still = why.GAPS.reason().model_dump(), why.NEVER_STILL.reason(seconds=2).model_dump()
    plane = why.OUT_OF_PLANE.reason(defined=0.41).model_dump()
    older: dict[str, Any] = {"id": None, "params": {}, "text": OLDER_TEXT}
    body: dict[str, Any] = {"curves": [], "error": None, "uncertainty_note": detail.NO_UNCERTAINTY_NOTE,
            "balance_missing": "in English", "balance_missing_reason": still,
            "quality": {"parts": [], "advice": [], "analysis_reasons": ["in English", OLDER_TEXT],
                        "analysis_reason_items": [gaps, older]},
            "uncertainty": {"angles": {"knee_flexion_L": {"withheld": "in English", "withheld_reason": plane},
                                       "knee_flexion_R": {"withheld": None, "withheld_reason": None}}},
            "validity": {"metrics": [{"name": "rom", "reason": detail.VALIDITY_REASONS[2]}]}}  # fmt: skip
    shown = detail.in_language(body, translator("es"))
    assert shown["quality"]["analysis_reasons"] == ["faltan datos en las posiciones medidas", OLDER_TEXT]
    assert shown["quality"]["analysis_reason_items"] == [
        gaps | {"text": "faltan datos en las posiciones medidas"}, older]  # fmt: skip
    assert shown["balance_missing"].startswith("no hubo en total 2 s de pie sin moverse")
    assert shown["balance_missing_reason"] == still | {"params": {"seconds": 2.0}, "text": shown["balance_missing"]}
    withheld = "el ángulo solo está definido en el 41\u00a0% de las imágenes (el brazo o la pierna salió de su plano)"
    assert shown["uncertainty"]["angles"]["knee_flexion_L"] == {
        "withheld": withheld,
        "withheld_reason": plane | {"text": withheld},
    }
    assert shown["uncertainty"]["angles"]["knee_flexion_R"] == {"withheld": None, "withheld_reason": None}
    assert shown["uncertainty_note"].startswith("El archivo de la sesión no guarda la incertidumbre")
    assert shown["validity"]["metrics"][0]["reason"] == (
        "En la imagen de una cámara no se ve un giro del brazo sobre su propio eje."
    )
    english = detail.in_language(body, translator("en"))
    assert english["quality"]["analysis_reasons"] == ["the measured positions have gaps", OLDER_TEXT]
    assert english["balance_missing"].startswith("the patient never stood still with both feet down for 2 s")
    assert body["quality"]["analysis_reasons"] == ["in English", OLDER_TEXT], "the stored body is kept"


def test_a_patient_reads_why_a_session_failed_in_their_language(client, db_session, upload, auth_headers):
    from backend.sessions.models import ExerciseSession

    session_id, patient, therapist = upload(make_khs_at_distance(seed=1), "squat")
    row = db_session.get(ExerciseSession, session_id)
    row.status, row.error = "failed", "AnalysisError: the recording has 1 frame(s); at least 2 are needed"
    patient.locale = "fr"
    db_session.flush()
    said = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(patient)).json()["error"]
    assert said == "L’analyse n’a pas pu utiliser cet enregistrement.", said
    listed = client.get(f"/api/v1/sessions?patient_id={patient.id}", headers=auth_headers(patient)).json()["items"]
    assert [s["error"] for s in listed] == [said]
    assert _detail(client, session_id, auth_headers(patient))["error"] == said
    clinic = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(therapist)).json()["error"]
    assert clinic == "The analysis could not use this recording: the recording has 1 frame(s); at least 2 are needed"


@pytest.mark.parametrize("locale", ["de", "es", "fr"])
def test_a_patient_reads_why_the_replay_failed_in_their_language(client, db_session, upload, auth_headers, locale):
    from backend.jobs.models import Job
    from backend.replay.jobs import job_key

    session_id, patient, therapist = upload(make_khs_at_distance(seed=1), "squat")
    trace = "StoredObjectMissing: session/ab12 is not in the store\nTraceback (most recent call last): ..."
    db_session.add(Job(kind="replay", key=job_key(session_id), payload={"session_id": session_id}, status="failed",
                       attempts=6, max_attempts=6, error=trace))  # fmt: skip
    patient.locale = locale
    db_session.flush()
    state = client.get(f"/api/v1/sessions/{session_id}/replay/state", headers=auth_headers(patient)).json()
    t = translator(locale)
    sentence = t.gettext("%(what)s.", what=t.gettext("The session's file is missing from the object store"))
    tried = t.ngettext("%(reason)s (tried once)", "%(reason)s (tried %(num)d times)", 6, reason=sentence)
    assert state == {"state": "failed", "detail": tried}
    assert "ab12" not in state["detail"] and "Traceback" not in state["detail"], state["detail"]
    clinic = client.get(f"/api/v1/sessions/{session_id}/replay/state", headers=auth_headers(therapist)).json()
    assert clinic["detail"] == (
        "The session's file is missing from the object store (run `coach-server storage "
        "check`): session/ab12 is not in the store (tried 6 times)"
    )


def test_a_patient_reads_how_each_indicator_was_scored_in_their_language(client, db_session, upload, auth_headers):
    from sqlalchemy import select

    from backend.sessions.models import SessionMetric

    session_id, patient, _ = upload(make_processed_khs("seated_knee_extension", 3, seed=3), "seated_knee_extension")
    stored = db_session.scalar(select(SessionMetric.document).where(SessionMetric.session_id == session_id))
    assert stored["schema_version"] == SCHEMA_VERSION == 6
    assert all(i["basis"]["id"] and i["basis"]["text"] is None for i in stored["indicators"].values()), "ids stored"
    english = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(patient)).json()["metrics"]
    patient.locale = "de"
    db_session.flush()
    german = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(patient)).json()["metrics"]
    french = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(patient) | {"Accept-Language": "fr"})
    french = french.json()["metrics"]
    for name in ("flexibility", "endurance", "strength", "balance"):
        en, de, fr = (doc["indicators"][name]["basis"] for doc in (english, german, french))
        assert (de["id"], de["params"]) == (fr["id"], fr["params"]) == (en["id"], en["params"]), name
        assert len({en["text"], de["text"], fr["text"]}) == 3, (name, en, de, fr)
    flexibility = german["indicators"]["flexibility"]["basis"]
    assert flexibility["id"] == "flexibility_normal_range" and flexibility["params"]["angle"] in detail_angles()
    assert flexibility["text"].startswith(angle_words(flexibility["params"]["angle"], "de") + ": mittlere"), flexibility
    assert french["indicators"]["balance"]["basis"]["text"] == (
        "oscillation du buste et des hanches en position debout\u00a0: 1 cm/s donnent 100 points, 6 cm/s en donnent 0"
    )
    progress = client.get(f"/api/v1/patients/{patient.id}/progress", headers=auth_headers(patient)).json()
    assert progress["points"][-1]["indicators"]["endurance"]["basis"] == german["indicators"]["endurance"]["basis"]


def test_an_english_basis_stored_before_ids_is_read_in_the_readers_language(client, db_session, upload, auth_headers):
    from sqlalchemy import select

    from backend.sessions.models import SessionMetric

    session_id, patient, therapist = upload(make_processed_khs("seated_knee_extension", 3, seed=3),
                                            "seated_knee_extension")  # fmt: skip
    metric = db_session.scalar(select(SessionMetric).where(SessionMetric.session_id == session_id))
    doc = dict(metric.document) | {"schema_version": 3}
    doc["indicators"] = {name: item | {"basis": text} for (name, item), text in zip(doc["indicators"].items(), (
        "median amplitude of knee_flexion_R against the normal range 0..90 deg", "repetitions against the target of 3",
        "movement speed (deg/s); no earlier session to compare with", OLDER_TEXT), strict=True)}  # fmt: skip
    metric.document = doc
    patient.locale = "de"
    db_session.flush()
    german = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(patient)).json()["metrics"]
    bases = {name: item["basis"] for name, item in german["indicators"].items()}
    assert bases["flexibility"] == {"id": "flexibility_normal_range",
                                    "params": {"angle": "knee_flexion_R", "low": 0, "high": 90},
                                    "text": "Beugung des rechten Knies: mittlere Bewegungsweite (Median der "
                                    "Wiederholungen) im Vergleich zum Normalbereich von 0 bis 90°"}  # fmt: skip
    assert bases["endurance"] == {"id": "endurance_target", "params": {"target": 3},
                                  "text": "Wiederholungen im Vergleich zum Ziel von 3"}  # fmt: skip
    assert bases["balance"] == {"id": None, "params": {}, "text": OLDER_TEXT}, "a text no message matches stays"
    clinic = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(therapist)).json()["metrics"]
    assert (
        clinic["indicators"]["strength"]["basis"]["text"] == "movement speed (°/s); no earlier session to compare with"
    )
    db_session.refresh(metric)
    assert metric.document == doc, "reading upgrades the answer, not the stored document"


def detail_angles() -> set[str]:
    from backend.session_texts.session_detail import ANGLE_WORDS

    return set(ANGLE_WORDS)


def angle_words(angle: str, locale: str) -> str:
    from backend.session_texts.session_detail import angle_label

    return angle_label(angle, translator(locale))
