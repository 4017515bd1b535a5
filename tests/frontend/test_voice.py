"""The live set speaks (issue 23, point 1): the exercise and its first instruction at Start, each count, halfway and
last-repetition encouragement, the end result in one sentence, each the same words the page shows; the patient's
on/off and volume are kept on the server, and muting stops the speaking at once.

The utterances are observed in Chromium by wrapping speechSynthesis.speak before the page's scripts run; the live
loop is driven by a paired device speaking the agent's protocol (tests.frontend.test_never_silent.AgentLink)."""

from __future__ import annotations

import re
import uuid
from typing import Any

import httpx
import pytest
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import expect

from tests.backend.khs_files import make_khs
from tests.frontend.conftest import THERAPIST, api_client, login, open_page, shot
from tests.frontend.test_live_set import NAME, PASSWORD
from tests.frontend.test_never_silent import EXERCISE, LOAD_MS, AgentLink, _now_iso, patient_with_device

pytestmark = pytest.mark.browser
GOAL = 6
OBSERVE = """
window.__spoken = [];
window.__cancelled = 0;
if (window.speechSynthesis) {
  const speak = speechSynthesis.speak.bind(speechSynthesis), cancel = speechSynthesis.cancel.bind(speechSynthesis);
  speechSynthesis.speak = (u) => { __spoken.push({ text: u.text, lang: u.lang, volume: u.volume }); speak(u); };
  speechSynthesis.cancel = () => { __cancelled += 1; cancel(); };
}
"""


def _spoken(page) -> list[dict[str, Any]]:
    return page.evaluate("window.__spoken")


def _texts(page) -> list[str]:
    return [u["text"] for u in _spoken(page)]


@pytest.fixture
def voice_page(browser, live_server):
    with open_page(browser, live_server.url, 1366, 900, init_script=OBSERVE) as page:
        yield page


def _voice(base: str, email: str, pid: int) -> dict[str, Any]:
    with httpx.Client(base_url=base, timeout=30) as c:
        c.post("/api/v1/auth/login", json={"email": email, "password": PASSWORD}).raise_for_status()
        return c.get(f"/api/v1/patients/{pid}/voice").json()


def _saved(pid: int):
    """Matches the page's answer to saving the voice setting (PUT /patients/{pid}/voice)."""
    return lambda r: r.request.method == "PUT" and r.url.endswith(f"/api/v1/patients/{pid}/voice")


def test_the_set_is_spoken_as_shown_and_the_setting_is_kept(voice_page, live_server):
    page, base = voice_page, live_server.url
    email, pid, token = patient_with_device(base, target=GOAL)
    link = AgentLink(base, token)
    try:
        login(page, email, PASSWORD)
        toggle = page.locator("#voice-toggle")
        expect(toggle).to_have_attribute("aria-pressed", "true", timeout=LOAD_MS)  # on by default for patients
        link.connect()
        expect(page.locator("#agent-status")).to_have_attribute("data-state", "online", timeout=LOAD_MS)
        page.get_by_role("button", name=re.compile(f"^Start {NAME}, set 1 of 2")).click()
        title, instruction = page.locator("#live-h").inner_text(), page.locator("#live-instruction").inner_text()
        assert instruction, "the first instruction of the library is shown at Start"
        page.wait_for_function("() => window.__spoken.length >= 1")
        assert _texts(page) == [f"{title}. {instruction}"]  # said = shown
        start, sid = link.command(), str(uuid.uuid4())
        cheers = {}
        for n in range(1, GOAL + 1):
            link.progress(start, "recording", n, sid, elapsed_s=2.0 * n)
            expect(page.locator("#live-count .n")).to_have_text(str(n))
            cheer = page.locator("#live-cheer")
            if cheer.count():
                cheers[n] = cheer.inner_text()
        assert set(cheers) == {3, 5}, cheers  # halfway (3 of 6) and before the last one (5 of 6)
        expected = [f"{title}. {instruction}"]
        for n in range(1, GOAL + 1):
            expected += [str(n)] + ([cheers[n]] if n in cheers else [])
        page.wait_for_function(f"() => window.__spoken.length >= {len(expected)}")
        assert _texts(page) == expected
        link.progress(start, "ended", GOAL, sid, elapsed_s=14.0, reason="target")
        stored = link.upload(make_khs(EXERCISE, GOAL, seed=11, session_id=sid, created_at=_now_iso()))
        expect(page.locator("#live-result")).to_contain_text("Saved", timeout=30_000)
        page.wait_for_function(f"() => window.__spoken.length >= {len(expected) + 1}")
        end = page.locator("#live-ended").inner_text()
        assert _texts(page)[-1] == end and str(min(stored["repetitions"], GOAL)) in end, (_texts(page), stored)
        assert {u["lang"] for u in _spoken(page)} == {"en-GB"}
        assert {u["volume"] for u in _spoken(page)} == {1.0}
        shot(page, "voice-ended")
        bad = [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]
        assert not bad, bad

        # volume: remembered on the server, used for the next utterance
        with page.expect_response(_saved(pid)):  # the setting is saved 0.4 s after the last change
            page.locator("#voice-volume").fill("40")
        expect(page.locator("#voice-volume")).to_have_value("40")
        assert _voice(base, email, pid)["volume"] == pytest.approx(0.4)
        page.get_by_role("button", name="Close").click()
        heard = len(_spoken(page))
        page.get_by_role("button", name=re.compile(f"^Start {NAME}, set 2 of 2")).click()
        page.wait_for_function(f"() => window.__spoken.length > {heard}")
        assert _spoken(page)[-1]["volume"] == pytest.approx(0.4)

        # muting: nothing more is queued, what was queued is cancelled, and it stays off after a reload
        start, sid = link.command(), str(uuid.uuid4())
        link.progress(start, "recording", 1, sid, elapsed_s=2.0)
        page.wait_for_function(f"() => window.__spoken.length > {heard + 1}")
        cancelled = page.evaluate("window.__cancelled")
        with page.expect_response(_saved(pid)) as saved:
            toggle.click()
        expect(toggle).to_have_attribute("aria-pressed", "false")
        expect(toggle).to_have_text("Voice off")
        assert page.evaluate("window.__cancelled") == cancelled + 1
        heard = len(_spoken(page))
        for n in (2, 3):
            link.progress(start, "recording", n, sid, elapsed_s=2.0 * n)
            expect(page.locator("#live-count .n")).to_have_text(str(n))
        assert len(_spoken(page)) == heard, _texts(page)[heard:]
        assert saved.value.ok, saved.value.status
        assert _voice(base, email, pid)["enabled"] is False
        page.reload()
        expect(page.locator("#voice-toggle")).to_have_attribute("aria-pressed", "false", timeout=LOAD_MS)
        assert not page.js_errors, page.js_errors
    finally:
        link.close()


def test_the_therapist_sets_the_patients_voice_beside_the_plan(page, live_server):
    email, pid, _ = patient_with_device(live_server.url)
    tara, _ = api_client(live_server.url, THERAPIST)
    admin, headers = api_client(live_server.url, "admin@demo.clinic")
    try:
        tid = tara.get("/api/v1/users/me").json()["id"]
        r = admin.put(f"/api/v1/patients/{pid}/therapists/{tid}", headers=headers)
    finally:
        admin.close()
        tara.close()
    assert r.status_code == 204, r.text
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.goto(f"/therapist/patients/{pid}")
    form = page.locator("#voice-setting")
    expect(form).to_be_visible(timeout=LOAD_MS)
    expect(page.locator("#voice-setting-on")).to_be_checked()
    page.locator("#voice-setting-volume").fill("60")
    page.locator("#voice-setting-on").uncheck()
    page.get_by_role("button", name="Save voice").click()
    expect(page.locator("#voice-setting-msg")).to_contain_text("Saved")
    assert _voice(live_server.url, email, pid) | {"updated_at": None} == {
        "patient_id": pid, "enabled": False, "volume": 0.6, "updated_at": None}  # fmt: skip
    bad = [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]
    assert not bad, bad
