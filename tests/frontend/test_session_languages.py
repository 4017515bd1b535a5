"""The session page and the 3D replay page in the reader's language (issue 23, point 2), in Chromium at 1366 and 390 px
(pairwise, REPLAY_CASES): the replay page of a patient who reads German, Spanish or French (its texts, checkboxes
and legend, the numbers), and the session page of a therapist whose browser asks for one of them once the therapist
pages have a catalogue in that language (a second server on the same database with COACH_LOCALE_DIR: the shipped
catalogues plus a therapist.po per language translating a few headings): the server's texts a patient also reads
(quality labels, notes, camera advice, the curves' angle names and kinds, the analysis' reasons written from their
ids) come from the shipped catalogues. Screenshots in /tmp/shots, axe-core 0 serious/critical, no sideways
scrolling."""

from __future__ import annotations

import re
import uuid

import pytest
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import expect

from backend.demo import DEMO_PASSWORD
from backend.i18n import translator
from kinect_agent.analysis import reasons
from tests.backend.khs_files import make_khs_at_distance, make_processed_khs
from tests.catalogue_copies import copy_with_therapist_catalogues
from tests.frontend.conftest import (
    THERAPIST,
    api_client,
    open_page,
    run_server,
    shot,
    sign_in,
    upload_session,
)

pytestmark = pytest.mark.browser
HEIGHT = {1366: 900, 390: 844}

# what each language shows: the replay page (messages.po) and the session page's texts (the test's therapist.po and
# the shipped messages.po: the camera advice)
REPLAY = {
    "de": {"back": "← Zurück zu meiner Seite", "raw": "Rohes Skelett", "filtered": "Gefiltertes Skelett",
           "reps": "3 Wiederholungen", "legend": "Was die Farben zeigen"},
    "es": {"back": "← Volver a mi página", "raw": "Esqueleto sin filtrar", "filtered": "Esqueleto filtrado",
           "reps": "3 repeticiones", "legend": "Qué muestran los colores"},
    "fr": {"back": "← Retour à ma page", "raw": "Squelette brut", "filtered": "Squelette filtré",
           "reps": "3 répétitions", "legend": "Ce que montrent les couleurs"},
}  # fmt: skip
THERAPIST_WORDS = {
    "de": {"{part}:": "{part}:", "Data quality": "Datenqualität", "Camera advice": "Hinweise zur Kamera",
           "Uncertainty": "Unsicherheit", "Key numbers": "Kennzahlen", "Repetitions": "Wiederholungen"},
    "es": {"{part}:": "{part}:", "Data quality": "Calidad de los datos", "Camera advice": "Consejos sobre la cámara",
           "Uncertainty": "Incertidumbre", "Key numbers": "Cifras clave", "Repetitions": "Repeticiones"},
    "fr": {"{part}:": "{part}\u00a0:", "Data quality": "Qualité des données",
           "Camera advice": "Conseils pour la caméra", "Uncertainty": "Incertitude", "Key numbers": "Chiffres clés",
           "Repetitions": "Répétitions"},
}  # fmt: skip
# the server's texts of the session page a patient also reads (the shipped messages.po)
SERVER_WORDS = {
    "de": {"parts": ("Von der Kamera gesehener Körper", "Erfassungsfehler",
                     "Gleichmäßigkeit der gemessenen Knochenlängen"),
           "note": "Die Sitzungsdatei enthält keine Unsicherheit je Bild", "curve": "Beugung des linken Knies (°)",
           "legend": ("roh", "gefiltert")},
    "es": {"parts": ("Cuerpo visto por la cámara", "Errores de seguimiento",
                     "Estabilidad de las longitudes óseas medidas"),
           "note": "El archivo de la sesión no guarda la incertidumbre por imagen",
           "curve": "Flexión de la rodilla izquierda (°)", "legend": ("sin filtrar", "filtrada")},
    "fr": {"parts": ("Corps vu par la caméra", "Erreurs de suivi", "Stabilité des longueurs d’os mesurées"),
           "note": "Le fichier de la séance ne contient pas l’incertitude par image",
           "curve": "Flexion du genou gauche (°)",
           "legend": ("brute", "filtrée")},
}  # fmt: skip
ADVICE = {"de": "Sie waren etwa 1,1 m von der Kamera entfernt", "es": "Estaba a unos 1,1 m de la cámara",
          "fr": "Vous étiez à environ 1,1 m de la caméra"}  # fmt: skip


def _serious(page) -> list[str]:
    return [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]


def _fits(page) -> None:
    scroll, client = page.evaluate("[document.documentElement.scrollWidth, document.documentElement.clientWidth]")
    assert scroll <= client, f"{page.url} scrolls sideways: {scroll} > {client}"


@pytest.fixture(scope="module")
def readers(live_server):
    """{locale: (patient e-mail, session id)}: a patient of the demo therapist per language, each with a set filmed
    too close to the camera (camera advice)."""
    found = {}
    admin, headers = api_client(live_server.url, "admin@demo.clinic")
    try:
        tara, _ = api_client(live_server.url, THERAPIST)
        therapist_id = tara.get("/api/v1/users/me").json()["id"]
        tara.close()
        for locale in REPLAY:
            email = f"reads-{locale}-{uuid.uuid4().hex[:8]}@example.org"
            body = {"email": email, "role": "patient", "password": DEMO_PASSWORD, "full_name": "Léa Lang"}
            r = admin.post("/api/v1/users", json=body, headers=headers)
            assert r.status_code == 201, r.text
            pid = r.json()["id"]
            assert admin.put(f"/api/v1/patients/{pid}/therapists/{therapist_id}", headers=headers).status_code == 204
            r = admin.patch(f"/api/v1/patients/{pid}", json={"locale": locale}, headers=headers)
            assert r.status_code == 200 and r.json()["locale"] == locale, r.text
            stored = upload_session(live_server.url, email, "squat", 3, seed=7,
                                    data=make_khs_at_distance("squat", 3, seed=7, z_m=1.1))  # fmt: skip
            found[locale] = (email, stored["id"])
    finally:
        admin.close()
    return found


@pytest.fixture(scope="module")
def translated_server(live_server, tmp_path_factory):
    """A second server on the live server's database and object store whose therapist pages come in German and
    French (COACH_LOCALE_DIR)."""
    root = tmp_path_factory.mktemp("catalogues")
    locale_dir = copy_with_therapist_catalogues(root, THERAPIST_WORDS)
    with run_server(live_server.database_url, root, COACH_STORAGE_DIR=live_server.storage_dir,
                    COACH_LOCALE_DIR=str(locale_dir)) as base:  # fmt: skip
        yield base


# Pairwise, not every language at every width: each language is checked at one width and each width in at least
# one language on each page, and the two pages take opposite widths per language, so every (language, width) pair is
# still rendered by one of them. No case is reachable only in one combination: the texts come from the catalogue
# whatever the width, and the layout at a width does not depend on which catalogue filled it (the longest texts,
# German and French, are each checked at 390 px on one page).
REPLAY_CASES = [("de", 1366), ("es", 390), ("fr", 1366)]
SESSION_CASES = [("de", 390), ("es", 1366), ("fr", 390)]


@pytest.mark.parametrize(("locale", "width"), REPLAY_CASES)
def test_the_patient_sees_the_replay_page_in_their_language(browser, live_server, readers, locale, width):
    email, session_id = readers[locale]
    words = REPLAY[locale]
    with open_page(browser, live_server.url, width, HEIGHT[width]) as page:
        sign_in(page, email)
        page.goto(f"/therapist/sessions/{session_id}/replay")
        expect(page.locator("html")).to_have_attribute("lang", locale)
        expect(page.locator("#replay-info")).to_contain_text(words["reps"])
        expect(page.locator("main p a").first).to_have_text(words["back"])
        expect(page.locator("label", has=page.locator("#show-raw"))).to_have_text(words["raw"])
        expect(page.locator("label", has=page.locator("#show-filtered"))).to_have_text(words["filtered"])
        expect(page.locator("ul.legend")).to_have_attribute("aria-label", words["legend"])
        page.frame_locator("#viewer").locator("canvas").first.wait_for(state="visible", timeout=60_000)
        page.uncheck("#show-raw")  # the filtered skeleton alone: built by a worker, then played
        expect(page.locator("#viewer")).to_have_attribute("src", re.compile("layer%3Dfiltered"), timeout=60_000)
        shot(page, f"replay_{locale}_{width}")
        assert not _serious(page), f"axe-core on the {locale} replay page at {width} px"
        _fits(page)
        assert not page.js_errors, page.js_errors


@pytest.mark.parametrize(("locale", "width"), SESSION_CASES)
def test_the_therapist_sees_the_session_page_in_their_language(browser, translated_server, readers, locale, width):
    _, session_id = readers[locale]
    words, server = THERAPIST_WORDS[locale], SERVER_WORDS[locale]
    with open_page(browser, translated_server, width, HEIGHT[width], locale=f"{locale}-{locale.upper()}") as page:
        sign_in(page, THERAPIST)
        page.goto(f"/therapist/sessions/{session_id}")
        expect(page.locator("html")).to_have_attribute("lang", locale)
        expect(page.locator("#quality-h")).to_have_text(words["Data quality"])
        parts = page.locator("#quality-parts li")
        expect(parts).to_have_count(3)
        for i, label in enumerate(server["parts"]):
            expect(parts.nth(i)).to_contain_text(label + ("\u00a0:" if locale == "fr" else ":"))
        advice = page.locator('#advice li[data-code="too_close"]')
        expect(advice).to_contain_text(ADVICE[locale])
        expect(page.locator("#advice h3")).to_have_text(words["Camera advice"])
        page.click("#processing summary")
        expect(page.locator("#processing-body")).to_contain_text(server["note"])
        first = page.locator("#curves figure").first  # the angle's name and the kinds, in the reader's words
        expect(first.locator("figcaption")).to_have_text(server["curve"])
        expect(first.locator(".legendtext")).to_have_text(list(server["legend"]))
        page.locator("#numbers dt").first.wait_for()
        shot(page, f"session_{locale}_{width}")
        assert not _serious(page), f"axe-core on the {locale} session page at {width} px"
        _fits(page)
        assert not page.js_errors, page.js_errors


@pytest.fixture(scope="module")
def seated(live_server, readers):
    """{locale: session id}: a seated set of each language's patient (balance not measured: not_standing)."""
    data = make_processed_khs("seated_knee_extension", 3, seed=3)
    return {locale: upload_session(live_server.url, email, "seated_knee_extension", 3, seed=3, data=data)["id"]
            for locale, (email, _) in readers.items()}  # fmt: skip


@pytest.mark.parametrize("locale", ["de", "es", "fr"])
def test_the_session_page_says_why_balance_was_not_measured_in_the_readers_language(
    browser, translated_server, seated, locale
):
    said = translator(locale).gettext(reasons.NOT_STANDING.message)
    assert said != reasons.NOT_STANDING.message, "the shipped catalogue translates it"
    with open_page(browser, translated_server, 1366, HEIGHT[1366], locale=f"{locale}-{locale.upper()}") as page:
        sign_in(page, THERAPIST)
        page.goto(f"/therapist/sessions/{seated[locale]}")
        expect(page.locator("html")).to_have_attribute("lang", locale)
        expect(page.locator(".stat .reasons", has_text=said)).to_have_count(1, timeout=60_000)
        shot(page, f"session_seated_{locale}_1366")
        assert not page.js_errors, page.js_errors
