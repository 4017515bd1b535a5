"""The patient page in each language, in Chromium: every text of the page in that language (no English left), dates
in its format, no axe-core serious or critical violation, no sideways scrolling at 1366, 768 and 390 px, and the
header's Language select changing it; a full-page screenshot of each in /tmp/shots to look at."""

from __future__ import annotations

import re

import pytest
from axe_playwright_python.sync_playwright import Axe

from tests.frontend.conftest import PATIENT, open_page, shot, sign_in

pytestmark = pytest.mark.browser

HEIGHT = {1366: 900, 768: 1024, 390: 844}
# texts of the page that show once its data has loaded, per language
EXPECTED = {
    "de": ("Ihre Übungen diese Woche", "Ratschläge von Ihrem Therapeuten", "Heute:", "Als Tabelle zeigen"),
    "es": ("Sus ejercicios de esta semana", "Consejos de su fisioterapeuta", "Hoy:", "Ver como tabla"),
    "fr": (
        "Vos exercices de la semaine",
        "Conseils de votre kinésithérapeute",
        "Aujourd’hui\u00a0:",
        "Afficher en tableau",
    ),
}
# English sentences of the page that must not be left untranslated
ENGLISH = ("Your exercises this week", "Advice from your therapist", "Today:", "Show as table", "times this week",
           "How you are doing", "Sign out", "Good morning", "Good afternoon", "Good evening", "well done")  # fmt: skip


@pytest.fixture(scope="module")
def patient_page(browser, live_server):
    """(Rose's page in a logged-in context, the setter of her language); her language is set back to the browser's
    afterwards."""
    with open_page(browser, live_server.url, 1366, 900) as page:
        csrf = sign_in(page, PATIENT)

        def set_locale(locale: str | None) -> None:
            answer = page.context.request.patch(f"/api/v1/patients/{live_server.patient_id}",
                                                data={"locale": locale}, headers={"X-CSRF-Token": csrf})  # fmt: skip
            assert answer.ok, answer.text()

        yield page, set_locale
        set_locale(None)


def _load(page, width: int) -> None:
    page.set_viewport_size({"width": width, "height": HEIGHT[width]})
    page.goto("/patient")
    page.wait_for_load_state("networkidle")
    page.locator("#last-sentence").wait_for()
    page.locator("#plan li[data-exercise]").first.wait_for()
    page.locator(".js-plotly-plot .main-svg").first.wait_for()


@pytest.mark.parametrize("width", (1366, 768, 390))
@pytest.mark.parametrize("locale", ("de", "es", "fr"))
def test_patient_page_in_each_language(patient_page, locale, width):
    page, set_locale = patient_page
    set_locale(locale)
    _load(page, width)
    shot(page, f"patient_{locale}_{width}")
    assert page.get_attribute("html", "lang") == locale
    text = page.inner_text("body")
    for expected in EXPECTED[locale]:
        assert expected in text, f"{expected!r} missing from the {locale} page"
    left = [english for english in ENGLISH if english in text]
    assert not left, f"English left on the {locale} page: {left}"
    month = re.compile({"de": r"\d+\. [A-ZÄÖÜ][a-zäöü]+", "es": r"\d+ de [a-z]+", "fr": r"\d+ [a-zéû]+"}[locale])
    assert month.search(page.inner_text("#advice")), page.inner_text("#advice")  # the advice's date, per locale
    violations = [v for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]
    assert not violations, [(v["id"], [n["target"] for n in v["nodes"][:3]]) for v in violations]
    scroll, client = page.evaluate("[document.documentElement.scrollWidth, document.documentElement.clientWidth]")
    assert scroll <= client, f"the {locale} page scrolls sideways at {width} px: {scroll} > {client}"
    assert not page.js_errors, page.js_errors


def test_the_language_select_changes_the_page_and_is_kept(patient_page):
    page, set_locale = patient_page
    set_locale(None)
    _load(page, 390)
    select = page.locator("header #language")
    box = select.bounding_box()
    assert box is not None and box["x"] + box["width"] <= 390 and box["height"] >= 40, box  # in view, easy to hit
    with page.expect_navigation():
        select.select_option("es")
    page.locator("#last-sentence").wait_for()
    assert page.get_attribute("html", "lang") == "es" and "Sus ejercicios de esta semana" in page.inner_text("body")
    page.reload()
    assert page.locator("header #language").input_value() == "es"
    assert not page.js_errors, page.js_errors
