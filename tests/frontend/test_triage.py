"""The therapist dashboard's triage end to end: rows in the server's attention order, "Now" only above the threshold."""

from __future__ import annotations

from typing import Any

import pytest
from playwright.sync_api import expect

from backend.sessions.triage import NOW_AT
from tests.frontend.conftest import THERAPIST, login, shot

pytestmark = pytest.mark.browser


def _dashboard(page) -> list[dict[str, Any]]:
    """Returns the rows the dashboard API gives the logged-in therapist, in its order."""
    return page.evaluate("async () => (await (await fetch(Coach.url('/api/v1/dashboard?limit=200'))).json()).items")


def test_dashboard_rows_follow_the_score_and_only_urgent_patients_show_now(page, live_server):
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    rows = page.locator("#patients tbody tr[data-patient-id]")
    rows.first.wait_for()
    api = _dashboard(page)
    expect(rows).to_have_count(len(api))
    shown = page.eval_on_selector_all(
        "#patients tbody tr[data-patient-id]",
        "trs => trs.map(tr => [Number(tr.dataset.patientId), Number(tr.dataset.attentionScore),"
        " tr.querySelector('.pill').textContent])",
    )
    assert [pid for pid, _, _ in shown] == [r["patient_id"] for r in api]
    scores = [score for _, score, _ in shown]
    assert scores == sorted(scores, reverse=True), shown
    for pid, score, pill in shown:
        assert (pill == "Now") == (score >= NOW_AT), (pid, score, pill)
    assert sum(pill == "Now" for _, _, pill in shown) < len(shown), shown  # it singles patients out
    for row, r in zip(rows.all(), api, strict=True):
        for reason in r["attention_reasons"]:
            expect(row.locator("td.attention")).to_contain_text(reason)
    assert not page.js_errors


def test_indicator_trends_have_a_text_alternative_and_missing_balance_says_why(page, live_server):
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.locator("#patients tbody tr[data-patient-id]").first.wait_for()
    rose = next(r for r in _dashboard(page) if r["patient_id"] == live_server.patient_id)
    row = page.locator(f'#patients tbody tr[data-patient-id="{rose["patient_id"]}"]')
    for t in rose["indicator_trends"].values():
        if t["direction"]:
            expect(row.get_by_role("img", name=t["text"])).to_be_visible()
    if rose["balance_missing"]:
        expect(row.locator(".why-missing")).to_have_text(rose["balance_missing"])
    assert not page.js_errors


@pytest.mark.parametrize("width", [1366, 390])
def test_dashboard_fits_the_width(page, live_server, width):
    page.set_viewport_size({"width": width, "height": 900})
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.locator("#patients tbody tr[data-patient-id]").first.wait_for()
    page_scroll = page.evaluate("document.documentElement.scrollWidth - document.documentElement.clientWidth")
    assert page_scroll <= 0, f"the page scrolls sideways by {page_scroll} px at {width} px"
    shot(page, f"triage_dashboard_{width}")


def _number(x: float, digits: int, locale: str) -> str:
    """Returns x as Intl.NumberFormat(tag, {maximumFractionDigits: digits}) writes it: it rounds the number's shortest
    decimal form (JavaScript's and Python's repr: 120.85, not the double's 120.8499…) half away from zero, grouped."""
    import decimal

    from babel.numbers import format_decimal

    with decimal.localcontext() as ctx:
        ctx.rounding = decimal.ROUND_HALF_UP
        return format_decimal(decimal.Decimal(repr(x)), format="#,##0." + "#" * digits if digits else "#,##0",
                              locale=locale)  # fmt: skip


def _measured(name: str, ind: dict[str, Any], v: float, locale: str) -> str:
    """Returns what the tooltip says of an indicator's value (frontend/static/therapist.js measured)."""
    if name == "flexibility":
        return f"{_number(v, 1, locale)}°"
    if name == "endurance":
        return _number(v, 1, locale)
    if name == "strength":
        rise = (ind.get("basis") or {}).get("id") == "strength_rise_time"
        return f"{_number(v, 2, locale)} s" if rise else f"{_number(v, 1, locale)} °/s"
    return f"{_number(100 * v, 1, locale)} cm/s"


@pytest.mark.parametrize("locale", ["en", "de"])
def test_indicator_tooltips_give_value_and_earlier_median_in_the_pages_number_format(page, live_server, locale):
    """The tooltip's value and earlier median with their unit, written as the page's language writes numbers
    (German: the page's locale set in its messages JSON, as a German therapist.po would give it)."""
    import re

    def as_locale(route):
        body = route.fetch().text()
        route.fulfill(body=re.sub(r'"locale": "en"', f'"locale": "{locale}"', body, count=1),
                      headers={"content-type": "text/html; charset=utf-8"})  # fmt: skip

    page.route(re.compile(r".*/therapist$"), as_locale)
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.locator("#patients tbody tr[data-patient-id]").first.wait_for()
    assert page.evaluate("I18n.locale") == locale
    cldr = {"en": "en_GB", "de": "de"}[locale]
    checked = 0
    for r in _dashboard(page):
        for k, ind in (r["latest_indicators"] or {}).items():
            if not ind or ind.get("score") is None or ind.get("previous") is None:
                continue
            title = page.locator(f'tr[data-patient-id="{r["patient_id"]}"] td.indicator').nth(
                ["flexibility", "endurance", "strength", "balance"].index(k)).get_attribute("title")  # fmt: skip
            value, previous = (_measured(k, ind, ind[v], cldr) for v in ("value", "previous"))
            said = f"; value {value}, earlier median {previous}"
            assert title is not None and title.endswith(said), (k, title, said)
            checked += 1
    assert checked >= 3, "the demo has earlier sessions to compare with"
    assert not page.js_errors
