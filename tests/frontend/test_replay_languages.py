"""The 3D replay in the patient's language, in Chromium: the replay page and viser's player inside it (its <html
lang> and title, the playback bar's names and tooltips, the scene tree's title and toggle, viser's browser notices),
with no English word of viser's that the app translates left; a screenshot of each in /tmp/shots to look at."""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import expect

from backend.i18n import translator
from tests.frontend.conftest import PATIENT, newest_session_id, open_page, shot, sign_in

pytestmark = pytest.mark.browser

# per language: the page's legend, then viser's words: pause and play buttons, speed, scene tree (title, show, hide)
WORDS = {
    "de": ("Gefiltertes Skelett", "Anhalten", "Abspielen", "Wiedergabegeschwindigkeit", "Szenenbaum",
           "Szenenbaum zeigen", "Szenenbaum ausblenden"),
    "fr": ("Squelette filtré", "Mettre en pause", "Lire", "Vitesse de lecture", "Arborescence de la scène",
           "Afficher l’arborescence de la scène", "Masquer l’arborescence de la scène"),
}  # fmt: skip
# the scene tree's rows: the floor, the raw and the filtered skeleton (their nodes /floor, /raw, /filtered)
NODES = {"de": ("Boden", "Rohes Skelett", "Gefiltertes Skelett"), "fr": ("Sol", "Squelette brut", "Squelette filtré")}
VISIBILITY = {"de": "Sichtbarkeit von Hand umschalten", "fr": "Changer la visibilité à la main"}  # the eye's tooltip
# viser's English words the player must not show in another language
VISER_ENGLISH = ("Playback speed", "Scene tree", "Software WebGL rendering detected", "WebGL is running in software",
                 "WebGL unavailable", "Could not detect browser version")  # fmt: skip


@pytest.mark.parametrize("locale", ("de", "fr"))
def test_the_patient_sees_the_replay_and_its_player_in_their_language(browser, live_server, locale):
    legend, pause, play, speed, tree, show_tree, hide_tree = WORDS[locale]
    with open_page(browser, live_server.url, 1366, 900) as page:
        csrf = sign_in(page, PATIENT)
        patient = f"/api/v1/patients/{live_server.patient_id}"
        assert page.context.request.patch(patient, data={"locale": locale}, headers={"X-CSRF-Token": csrf}).ok
        try:
            page.goto(f"/therapist/sessions/{newest_session_id(live_server.url, PATIENT)}/replay")
            expect(page.locator("#layers")).to_contain_text(legend)
            viewer = page.frame_locator("#viewer")
            viewer.locator("canvas").first.wait_for(state="visible", timeout=60_000)
            pause_button = viewer.locator("button:has(.tabler-icon-player-pause-filled)")
            expect(pause_button).to_have_attribute("aria-label", pause, timeout=30_000)
            frame = page.locator("#viewer").element_handle().content_frame()
            assert frame is not None
            assert frame.evaluate("document.documentElement.lang") == locale
            assert frame.title() == translator(locale).gettext("Session replay") != "Session replay", frame.title()
            expect(viewer.locator(f'input[aria-label="{speed}"]')).to_have_count(1)
            viewer.locator(f'input[aria-label="{speed}"]').hover()
            expect(viewer.get_by_role("tooltip")).to_have_text(speed)
            viewer.locator(f'button[aria-label="{show_tree}"]').click()
            expect(viewer.locator(f'button[aria-label="{hide_tree}"]')).to_have_count(1)
            expect(viewer.get_by_text(tree, exact=True).first).to_be_visible()
            for node, words in zip(("/floor", "/raw", "/filtered"), NODES[locale], strict=True):
                expect(viewer.locator(f'[data-scene-node="{node}"]')).to_contain_text(words)
            viewer.locator('[data-scene-node="/raw"] .tabler-icon-eye').hover()  # the row's eye, and the node's label
            # the scene tree button's tooltip may still be closing beside it (it was clicked just before)
            expect(viewer.get_by_role("tooltip").filter(has_text=VISIBILITY[locale])).to_have_text(VISIBILITY[locale])
            expect(viewer.get_by_text("/" + NODES[locale][1], exact=True).first).to_be_visible()
            pause_button.click()
            expect(viewer.locator("button:has(.tabler-icon-player-play-filled)")).to_have_attribute("aria-label", play)
            shot(page, f"replay-{locale}")
            shown = frame.evaluate("document.body.innerText + ' ' + [...document.querySelectorAll('[aria-label]')]"
                                   ".map(e => e.getAttribute('aria-label')).join(' ')")  # fmt: skip
            left = [w for w in VISER_ENGLISH if re.search(re.escape(w), shown)]
            assert not left, f"viser's English in the {locale} player: {left}"
            assert not page.js_errors, page.js_errors
        finally:
            page.context.request.patch(patient, data={"locale": None}, headers={"X-CSRF-Token": csrf})
