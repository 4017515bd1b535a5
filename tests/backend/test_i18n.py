"""Languages: the catalogues are complete (every message, every locale, the same placeholders), the pages come in the
patient's language (chosen by their therapist or themselves) or the browser's, and dates and numbers follow it."""

from __future__ import annotations

import datetime as dt
import json
import re
from typing import Any

import pytest
from babel.messages.catalog import Catalog

from backend.i18n import LOCALES, js_messages, negotiate, normalise, translator
from backend.i18n.catalogues import check, check_locale, extract, placeholders, unmarked_page_text
from tests.backend.session_rows import report

HTML = {"Accept": "text/html"}


def test_every_message_has_every_translation_with_the_same_placeholders():
    problems = check()
    assert problems == [], "\n".join(map(str, problems))


def test_the_check_names_a_missing_translation_and_different_placeholders():
    code = Catalog()
    code.add("You did %(n)s of %(goal)s.")
    code.add("Nothing here yet")
    code.add(("{n} set", "{n} sets"))
    po = Catalog(locale="de")
    po.add("You did %(n)s of %(goal)s.", "Sie haben %(n)s geschafft.")
    po.add(("{n} set", "{n} sets"), ("{n} Satz", ""))
    found = [str(p) for p in check_locale("de", code, po)]
    assert any("placeholders ['n'] != ['goal', 'n']" in p for p in found), found
    assert any("no translation of 'Nothing here yet'" in p for p in found), found
    assert any("no translation of '{n} set'" in p for p in found), found


def test_the_check_holds_french_to_a_no_break_space_before_colon_semicolon_and_marks():
    code = Catalog()
    for msgid in ("Saved: {n}", "Well done!", "Ready?", "Rest; then go on", "At 10:30, see %{y:.1f} s", "Today:"):
        code.add(msgid)
    po = Catalog(locale="fr")
    po.add("Saved: {n}", "Enregistré : {n}")  # a plain space
    po.add("Well done!", "Bravo!")  # no space
    po.add("Ready?", "Prêt\u202f?")
    po.add("Rest; then go on", "Reposez-vous\u00a0; puis continuez")
    po.add("At 10:30, see %{y:.1f} s", "À 10:30, voir %{y:.1f} s")  # a time and Plotly's format are not punctuation
    po.add("Today:", "Aujourd’hui\u00a0:")
    found = [str(p) for p in check_locale("fr", code, po)]
    assert len(found) == 2, found
    assert "'Saved: {n}': no no-break space before ':'" in found[0], found
    assert "'Well done!': no no-break space before '!'" in found[1], found
    german = Catalog(locale="de")
    german.add("Saved: {n}", "Gespeichert: {n}")
    assert [str(p) for p in check_locale("de", code, german) if "no-break" in str(p)] == []


def test_the_check_finds_unmarked_words_on_the_patients_pages_too(tmp_path):
    (tmp_path / "frontend/templates").mkdir(parents=True)
    (tmp_path / "frontend/static").mkdir(parents=True)
    (tmp_path / "frontend/templates/patient.html").write_text(
        '<h1>{{ _("Your exercises this week") }}</h1>\n<p>Kinect Home Coach</p>\n<p>Your next set</p>\n'
    )
    (tmp_path / "frontend/static/live.js").write_text(
        'say(I18n.t("Halfway there"));\nsay("One more to go");\nconsole.warn("worker failed twice");  '
        "// i18n: not shown\n")  # fmt: skip
    found = [str(p) for p in unmarked_page_text(tmp_path)]
    assert found == ["frontend/templates/patient.html:3: text not marked for translation: 'Your next set'",
                     "frontend/static/live.js:2: text not marked for translation: 'One more to go'"], found  # fmt: skip


def test_extraction_finds_python_template_and_script_messages():
    ids = {m.id if isinstance(m.id, str) else m.id[0] for m in extract() if m.id}
    assert "Page not found" in ids  # frontend/pages.py, N_
    assert "Your exercises this week" in ids  # patient.html
    assert "Please fill in both your e-mail address and your password." in ids  # login.js, I18n.t


def test_placeholders_of_both_styles():
    assert placeholders("%(n)d of %(goal)s, {name}") == {"n", "goal", "name"}


@pytest.mark.parametrize(
    ("header", "locale"),
    [
        ("de-DE,de;q=0.9,en;q=0.8", "de"),
        ("fr-CA", "fr"),
        ("pt-BR,es;q=0.5,de;q=0.4", "es"),
        ("en;q=0.2,fr;q=0.9", "fr"),
        ("zh-CN", "en"),
        ("", "en"),
        (None, "en"),
        ("de;q=0,es", "es"),
        ("*", "en"),
        ("x" * 300 + ",;;q=abc", "en"),
    ],
)
def test_accept_language_picks_the_preferred_supported_locale(header, locale):
    assert negotiate(header) == locale


def test_normalise_takes_the_language_of_a_tag():
    assert normalise("es_MX") == "es" and normalise("de-AT") == "de" and normalise("it") is None
    assert normalise("not a tag!") is None


def test_dates_and_numbers_follow_the_locale():
    day = dt.date(2026, 11, 27)
    assert translator("en").format_date(day) == "November 27, 2026"
    assert translator("de").format_date(day) == "27. November 2026"
    assert translator("es").format_date(day) == "27 de noviembre de 2026"
    assert translator("fr").format_date(day) == "27 novembre 2026"
    assert translator("de").format_number(1.5, 1) == "1,5" and translator("en").format_number(1.5, 1) == "1.5"
    assert translator("xx").locale == "en"


def test_plural_forms_per_locale():
    one, many = "%(num)d set", "%(num)d sets"
    assert translator("en").ngettext(one, many, 1) == "1 set"
    assert translator("en").ngettext(one, many, 0) == "0 sets"


def test_script_messages_are_only_those_of_scripts():
    fr = js_messages("fr")
    assert fr["locale"] == "fr" and fr["plural"] == "n > 1"
    assert "Please fill in both your e-mail address and your password." in fr["messages"]
    assert "Page not found" not in fr["messages"]  # a server message: not sent to the scripts
    assert js_messages("de")["plural"] == "n != 1"
    assert js_messages("en") == {"locale": "en", "plural": "n != 1", "messages": {}}


def _page_messages(html: str) -> dict[str, Any]:
    found = re.search(r'<script type="application/json" id="i18n-messages">(.*?)</script>', html, re.S)
    assert found, "the page carries no messages for its scripts"
    return json.loads(found.group(1))


def test_login_page_follows_the_browser_language(client):
    r = client.get("/", headers=HTML | {"Accept-Language": "es-ES,es;q=0.9"})
    assert r.status_code == 200
    assert '<html lang="es">' in r.text and "Bienvenido" in r.text and "Contraseña" in r.text
    assert _page_messages(r.text)["locale"] == "es"
    english = client.get("/", headers=HTML | {"Accept-Language": "ja"})
    assert '<html lang="en">' in english.text and "Welcome" in english.text


def test_error_page_follows_the_browser_language(client):
    r = client.get("/no/such/page", headers=HTML | {"Accept-Language": "fr"})
    assert r.status_code == 404 and "<h1>Page introuvable</h1>" in r.text and "Aller à la page d’accueil" in r.text


def test_therapist_sets_the_patient_language_and_the_patient_page_follows(
    client, make_patient_with_therapist, auth_headers
):
    patient, therapist = make_patient_with_therapist()
    r = client.patch(f"/api/v1/patients/{patient.id}", json={"locale": "de"}, headers=auth_headers(therapist))
    assert r.status_code == 200, r.text
    assert r.json()["locale"] == "de"
    page = client.get("/patient", headers=HTML | auth_headers(patient) | {"Accept-Language": "fr"})
    assert page.status_code == 200
    assert '<html lang="de">' in page.text and "Meine Übungen" in page.text
    assert '<option value="de" lang="de" selected>Deutsch</option>' in page.text
    assert _page_messages(page.text)["locale"] == "de"


def test_patient_changes_their_own_language_and_back_to_the_browser(client, make_user, auth_headers):
    patient = make_user("patient")
    headers = auth_headers(patient)
    assert (
        client.patch(f"/api/v1/patients/{patient.id}", json={"locale": "fr"}, headers=headers).json()["locale"] == "fr"
    )
    assert client.get(f"/api/v1/patients/{patient.id}", headers=headers).json()["locale"] == "fr"
    assert client.patch(f"/api/v1/patients/{patient.id}", json={"locale": None}, headers=headers).status_code == 200
    page = client.get("/patient", headers=HTML | headers | {"Accept-Language": "es"})
    assert '<html lang="es">' in page.text


def test_unknown_language_is_refused_naming_the_field(client, make_user, auth_headers):
    patient = make_user("patient")
    r = client.patch(f"/api/v1/patients/{patient.id}", json={"locale": "klingon"}, headers=auth_headers(patient))
    assert r.status_code == 422 and r.json()["error"] == "ValidationError" and "locale" in r.json()["detail"]


def test_another_patient_cannot_change_the_language(client, make_user, auth_headers):
    patient, other = make_user("patient"), make_user("patient")
    r = client.patch(f"/api/v1/patients/{patient.id}", json={"locale": "de"}, headers=auth_headers(other))
    assert r.status_code == 404


def test_therapist_pages_stay_english(client, make_patient_with_therapist, auth_headers):
    _, therapist = make_patient_with_therapist()
    page = client.get("/therapist", headers=HTML | auth_headers(therapist) | {"Accept-Language": "de"})
    assert page.status_code == 200 and '<html lang="en">' in page.text


@pytest.mark.parametrize("locale", LOCALES)
def test_each_locale_renders_the_patient_page(client, make_user, auth_headers, locale):
    patient = make_user("patient", full_name="Rosa Weber")
    headers = auth_headers(patient)
    client.patch(f"/api/v1/patients/{patient.id}", json={"locale": locale}, headers=headers)
    page = client.get("/patient", headers=HTML | headers)
    assert page.status_code == 200 and f'<html lang="{locale}">' in page.text
    assert "Rosa Weber" in page.text


def test_an_api_error_marked_for_translation_comes_in_the_asked_language(
    client, db_session, make_patient_with_therapist, auth_headers, exercise
):
    from backend.database import utcnow
    from backend.plans.models import Plan, PlanItem

    patient, therapist = make_patient_with_therapist()
    plan = Plan(patient_id=patient.id, therapist_id=therapist.id, title="p", start_date=utcnow().date())
    plan.items.append(PlanItem(exercise_id=exercise.id, sets=1, repetitions=8, frequency_per_week=3))
    db_session.add(plan)
    db_session.flush()
    # English: tests/backend/live/test_live_http.py (no Content-Language there)
    body, headers = {"plan_item_id": plan.items[0].id}, auth_headers(patient)
    r = client.post("/api/v1/live/start", json=body, headers=headers | {"Accept-Language": "de"})
    assert r.status_code == 409 and r.headers["content-language"] == "de"
    assert r.json() == {"error": "AgentOffline", "detail": "Ihr Computer zu Hause ist nicht verbunden: Bitte prüfen "
                        "Sie, ob er eingeschaltet und mit dem Internet verbunden ist"}  # fmt: skip


def test_every_hint_of_the_home_computer_is_in_the_scripts_catalogue():
    from kinect_agent.analysis import live

    hints = {value for name, value in vars(live).items() if name.startswith("HINT_") and isinstance(value, str)}
    assert len(hints) == 6
    for locale in LOCALES[1:]:
        messages = js_messages(locale)["messages"]
        assert hints <= set(messages), f"{locale}: {sorted(hints - set(messages))}"


def test_the_exercise_library_comes_in_the_asked_language(client, make_user, auth_headers, exercise):
    headers = auth_headers(make_user("patient"))
    english = client.get(f"/api/v1/exercises/{exercise.slug}", headers=headers).json()
    german = client.get(f"/api/v1/exercises/{exercise.slug}", headers=headers | {"Accept-Language": "de"}).json()
    assert german["name"] == translator("de").gettext(english["name"]) != english["name"]
    assert german["instructions"] == translator("de").gettext(english["instructions"]) != english["instructions"]
    listed = client.get("/api/v1/exercises", headers=headers | {"Accept-Language": "fr-FR"}).json()["items"]
    assert {e["name"] for e in listed} & {"Petite flexion des genoux", "Tendre le genou assis", "Squat profond"}


@pytest.mark.parametrize(
    ("locale", "expected"),
    [
        ("en", "On Saturday you did 6 of the 10 mini squats in your plan."),
        ("de", "Am Samstag haben Sie bei der Übung „Kleine Kniebeuge“ 6 von 10 Wiederholungen aus Ihrem Plan"),
        ("es", "El sábado hizo 6 de las 10 repeticiones de «Media sentadilla» de su plan."),
        ("fr", "Samedi, vous avez fait 6 des 10 répétitions de «\u202fPetite flexion des genoux\u202f» prévues."),
    ],
)
def test_advice_is_written_in_the_patient_language(locale, expected):
    from backend.suggestions.rules import evaluate

    saturday = dt.datetime(2026, 11, 21, 10, tzinfo=dt.UTC)
    doc = report(exercise="squat", repetitions=6, tempo_s_per_rep=3.0, quality={"ok": True})
    drafts = evaluate(doc, prescribed_reps=10, history=[], expected_per_week=None, now=saturday,
                      today=dt.date(2026, 11, 23), t=translator(locale))  # fmt: skip
    assert [d.rule for d in drafts] == ["fewer_reps"]
    assert drafts[0].text.startswith(expected), drafts[0].text


def test_advice_dates_and_numbers_follow_the_locale():
    from backend.suggestions.rules import evaluate, session_day

    long_ago = dt.datetime(2025, 3, 14, 10, tzinfo=dt.UTC)
    assert session_day(long_ago, dt.date(2026, 11, 23), translator("de")) == "am 14. März 2025"
    assert session_day(long_ago, dt.date(2026, 11, 23), translator("es")) == "el 14 de marzo de 2025"
    assert session_day(long_ago, dt.date(2026, 11, 23), translator("en")) == "on 14 March 2025"
    doc = report(exercise="squat", repetitions=10, tempo_s_per_rep=1.25, quality={"ok": True})
    now = dt.datetime(2026, 11, 21, 10, tzinfo=dt.UTC)
    fast = evaluate(doc, prescribed_reps=10, history=[], expected_per_week=None, now=now, t=translator("fr"))
    assert "environ 1,2 secondes" in fast[0].text, fast[0].text


def test_a_german_patient_gets_advice_in_german(db_session, make_user, exercise):
    import uuid

    from backend.sessions.models import ExerciseSession, SessionMetric
    from backend.suggestions.service import suggest_for_session

    patient = make_user("patient")
    patient.locale = "de"
    doc = report(exercise=exercise.slug, repetitions=10, rom_deg=80.0, tempo_s_per_rep=0.8,
                 quality={"ok": True, "tracked_fraction": 1.0, "outlier_fraction": 0.0, "reasons": []})  # fmt: skip
    row = ExerciseSession(client_session_id=uuid.uuid4(), patient_id=patient.id, exercise_id=exercise.id,
                          started_at=dt.datetime.now(dt.UTC), duration_s=30.0, n_frames=900, file_bytes=b"",
                          content_hash=uuid.uuid4().hex * 2)  # fmt: skip
    row.metric = SessionMetric(document=doc.model_dump(mode="json"), repetitions=10, rom_deg=80.0)
    db_session.add(row)
    db_session.flush()
    made = suggest_for_session(db_session=db_session, session=row, doc=doc)
    assert [s.rule for s in made] == ["too_fast"]
    assert made[0].text.startswith("Am ") and "etwa 0,8 Sekunden pro Wiederholung" in made[0].text, made[0].text


@pytest.mark.parametrize(
    ("locale", "consent", "script_text"),
    [
        (
            "de",
            "Das Video bleibt auf diesem Gerät.",
            "Wir können Sie nicht sehen. Bitte stellen Sie sich vor die Kamera.",
        ),
        ("es", "El vídeo nunca sale de este aparato.", "No le vemos. Póngase delante de la cámara."),
        ("fr", "La vidéo ne quitte jamais cet appareil.", "Nous ne vous voyons pas. Placez-vous devant la caméra."),
    ],
)
def test_camera_page_comes_in_the_patient_language(client, make_user, auth_headers, locale, consent, script_text):
    """The browser-camera set (consent in the template, the placement check's words in camera_text.js) follows the
    patient's chosen language, not the browser's."""
    patient = make_user("patient", full_name="Rosa Weber")
    headers = auth_headers(patient)
    assert client.patch(f"/api/v1/patients/{patient.id}", json={"locale": locale}, headers=headers).status_code == 200
    page = client.get("/patient/camera?item=1", headers=HTML | headers | {"Accept-Language": "en"})
    assert page.status_code == 200 and f'<html lang="{locale}">' in page.text
    assert consent in page.text and "The video never leaves this device" not in page.text
    messages = _page_messages(page.text)
    assert messages["locale"] == locale
    assert messages["messages"]["We cannot see you. Please step in front of the camera."] == script_text
    start = messages["messages"]["Start with this computer's camera"]
    assert start and start != "Start with this computer's camera"
