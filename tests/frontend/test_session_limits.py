"""The session page of a webcam session: the device in the key numbers and a box of the metrics one camera cannot
measure, each with its reason; a Kinect session shows no such box."""

from __future__ import annotations

import pytest
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import expect

from tests.backend.test_session_detail_device import _khs
from tests.frontend.conftest import PATIENT, THERAPIST, login, shot, upload_session

pytestmark = pytest.mark.browser
WIDTHS = {1366: 900, 768: 1024, 390: 844}
BLOCKING = ("serious", "critical")


@pytest.fixture(scope="module")
def webcam_front(live_server) -> int:
    """A squat filmed by a webcam from the front, uploaded as Rose: its range of motion is out of the image plane."""
    return upload_session(live_server.url, PATIENT, "squat", 3, seed=5, data=_khs("webcam", side=False))["id"]


@pytest.fixture(scope="module")
def kinect(live_server) -> int:
    return upload_session(live_server.url, PATIENT, "squat", 3, seed=6, data=_khs("kinect2", side=False))["id"]


def _open(page, session_id: int) -> None:
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.goto(f"/therapist/sessions/{session_id}")
    page.locator("#curves .js-plotly-plot").first.wait_for()


@pytest.mark.parametrize("width", WIDTHS)
def test_a_webcam_session_shows_its_device_and_limits(page, webcam_front, width):
    page.set_viewport_size({"width": width, "height": WIDTHS[width]})
    _open(page, webcam_front)
    box = page.locator("#limits")
    expect(box).to_be_visible()
    expect(page.locator("#limits-intro")).to_contain_text("ordinary camera (webcam), model pose_landmarker_lite")
    expect(page.locator("#limits-intro")).to_contain_text("filmed from the front")
    expect(box.locator("li[data-metric=rom]")).to_contain_text("Film the exercise from the side")
    expect(box.locator("li[data-metric=workspace]")).to_contain_text("assumed camera")
    expect(box.locator("li[data-metric=repetitions]")).to_have_count(0)
    expect(page.locator("#numbers")).to_contain_text("Recorded with")
    expect(page.locator("#numbers")).to_contain_text("not reliable from this view")
    # the sway is in metres, which the limits box flags: its key number says so too, not only the box above
    expect(page.locator("#numbers .stat", has_text="Balance (sway)")).to_contain_text(
        "from one camera: see the limits above"
    )
    shot(page, f"session_webcam_limits_{width}")
    violations = [v for v in Axe().run(page).response["violations"] if v["impact"] in BLOCKING]
    assert not violations, [(v["id"], v["help"]) for v in violations]
    assert page.evaluate("document.documentElement.scrollWidth <= document.documentElement.clientWidth")
    assert not page.js_errors


def test_a_kinect_session_has_no_limits_box(page, kinect):
    _open(page, kinect)
    expect(page.locator("#numbers")).to_contain_text("Kinect v2")
    expect(page.locator("#numbers")).not_to_contain_text("see the limits above")
    assert page.locator("#limits").is_hidden()
