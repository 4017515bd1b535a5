"""Every page at desktop, tablet and phone widths: no serious or critical axe-core violation, no horizontal
scrolling, chart labels large enough; a full-page screenshot of each in /tmp/shots to look at."""

from __future__ import annotations

from contextlib import ExitStack
from dataclasses import dataclass
from typing import Any

import pytest
from axe_playwright_python.sync_playwright import Axe

from tests.frontend.conftest import PATIENT, THERAPIST, newest_session_id, open_page, shot, sign_in

pytestmark = pytest.mark.browser

WIDTHS = (1366, 768, 390)
HEIGHT = {1366: 900, 768: 1024, 390: 844}
BLOCKING = ("serious", "critical")


@dataclass(frozen=True)
class PageCase:
    """One page: who opens it, its address (with {patient} and {session} filled in), what shows it has loaded."""

    name: str
    role: str  # "anonymous" | "patient" | "therapist"
    path: str
    ready: str | None = None  # a selector that appears once the page's data is shown
    chart_px: int | None = None  # the smallest chart label allowed, px (pages with charts)
    click: str | None = None  # a button pressed once the page is ready (a page state, e.g. an open form)


PAGES = (
    PageCase("login", "anonymous", "/", "#login-form"),
    PageCase("not_found", "anonymous", "/no/such/page", "h1"),
    PageCase("patient", "patient", "/patient", "#last-sentence", chart_px=20),
    PageCase("dashboard", "therapist", "/therapist", "#patients tbody tr[data-patient-id]"),
    PageCase(
        "patient_detail",
        "therapist",
        "/therapist/patients/{patient}",
        "#sessions tbody tr[data-session-id]",
        chart_px=14,
    ),  # fmt: skip
    PageCase("plan_form", "therapist", "/therapist/patients/{patient}", "#plan-items li", click="#plan-edit"),
    PageCase("session", "therapist", "/therapist/sessions/{session}", "#numbers dt", chart_px=14),
    PageCase("replay", "therapist", "/therapist/sessions/{session}/replay", '#replay-info:has-text("repetitions")'),
)


@pytest.fixture(scope="module")
def session_id(live_server) -> int:
    """The id of one of Rose's sessions (the newest)."""
    return newest_session_id(live_server.url, THERAPIST, live_server.patient_id)


@pytest.fixture(scope="module")
def role_pages(browser, live_server):
    """One browser page per role, logged in once for the module: {"anonymous", "patient", "therapist"}."""
    with ExitStack() as stack:
        pages = {}
        for role, email in (("anonymous", None), ("patient", PATIENT), ("therapist", THERAPIST)):
            page = stack.enter_context(open_page(browser, live_server.url, 1366, 900))
            if email is not None:
                sign_in(page, email)
            pages[role] = page
        yield pages


def _violations(page) -> list[dict[str, Any]]:
    results = Axe().run(page)
    return [v for v in results.response["violations"] if v["impact"] in BLOCKING]


def _describe(violations: list[dict[str, Any]]) -> str:
    lines = []
    for v in violations:
        lines.append(f"{v['id']} ({v['impact']}): {v['help']}")
        for node in v["nodes"][:5]:
            lines.append(f"    {' '.join(map(str, node['target']))}: {node['failureSummary'].splitlines()[-1].strip()}")
    return "\n".join(lines)


SMALLEST_CHART_TEXT = """() => {
  const sizes = [...document.querySelectorAll('.js-plotly-plot svg text')]
    .filter((t) => t.textContent.trim() && t.getBBox().width > 0)
    .map((t) => parseFloat(getComputedStyle(t).fontSize));
  return sizes.length ? Math.min(...sizes) : null;
}"""


@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize("case", PAGES, ids=[p.name for p in PAGES])
def test_page_is_accessible_and_fits_the_width(role_pages, live_server, session_id, case, width):
    page = role_pages[case.role]
    page.set_viewport_size({"width": width, "height": HEIGHT[width]})
    path = case.path.format(patient=live_server.patient_id, session=session_id)
    response = page.goto(path)
    assert response.status == (404 if case.name == "not_found" else 200), path
    page.wait_for_load_state("networkidle")
    if case.ready:
        page.locator(case.ready).first.wait_for()
    if case.chart_px:
        page.locator(".js-plotly-plot .main-svg").first.wait_for()
    if case.click:
        page.click(case.click)
    shot(page, f"{case.name}_{width}")

    violations = _violations(page)
    assert not violations, f"axe-core on {path} at {width} px:\n{_describe(violations)}"
    scroll, client = page.evaluate("[document.documentElement.scrollWidth, document.documentElement.clientWidth]")
    assert scroll <= client, f"{path} scrolls sideways at {width} px: {scroll} > {client}"
    if case.chart_px:
        smallest = page.evaluate(SMALLEST_CHART_TEXT)
        assert smallest is not None and smallest >= case.chart_px, f"chart labels of {smallest} px on {path}"
    assert not page.js_errors, page.js_errors
