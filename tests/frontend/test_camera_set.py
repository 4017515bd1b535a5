"""A camera set end to end in real headless Chromium, fed a video file as its camera: the patient's page offers
"Start with this computer's camera", the consent screen, the placement check with the skeleton over the mirrored
picture, the live count rising, the saved session (device `webcam`) on the server; and the faults the page names.

The camera: Sports2D's demo video (PyPI `sports2d` 0.8.34, BSD-3-Clause, (c) 2022 perfanalytics; one person walking
past, filmed from the side, a second on a box), made into a .y4m at test time (tests/fake_camera.py) and played by
Chromium's fake capture device in a loop. The landmarker runs the lite model on the CPU (?model=lite&delegate=CPU):
this machine's headless Chromium has no GPU.
"""

from __future__ import annotations

import re
import time
from collections.abc import Iterator
from contextlib import closing, contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

import httpx
import pytest
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import TimeoutError as PlaywrightTimeoutError
from playwright.sync_api import expect

from backend.camera import limits
from kinect_agent.formats import session_file
from tests.frontend.conftest import (
    CHROMIUM,
    NEW_PATIENT_PASSWORD,
    api_client,
    create_patient,
    login,
    open_page,
    plan_item,
    shot,
)

if TYPE_CHECKING:
    from tests.frontend.conftest import CheckedPage

pytestmark = pytest.mark.browser
PASSWORD = NEW_PATIENT_PASSWORD
EXERCISE, TARGET = "squat", 2
WIDTHS = ((1366, 900), (768, 1024), (390, 844))
PAGE = "/patient/camera"
SLOW_SAID_OR_FAST = (
    "() => CameraPage.state().fps >= 10 || "
    "document.getElementById('cam-note').textContent.includes('This computer is slow')"
)
NEXT_FRAME = "() => new Promise((done) => requestAnimationFrame(() => requestAnimationFrame(done)))"
KEPT_BATCHES = "CameraBuffer.batches(CameraPage.state().set_id).then((b) => b.length)"
WATCH_CSP = ("window.__csp = []; document.addEventListener('securitypolicyviolation', "
             "(e) => __csp.push([e.effectiveDirective, e.blockedURI]))")  # fmt: skip


def _axe_clean(page) -> None:
    results = Axe().run(page)
    bad = [
        f"{v['id']} ({v['impact']})" for v in results.response["violations"] if v["impact"] in ("serious", "critical")
    ]
    assert not bad, bad


def _shots(page, name: str) -> None:
    """Screenshots at 1366, 768 and 390 px (back to 1366 afterwards), each checked with axe-core."""
    for w, h in WIDTHS:
        page.set_viewport_size({"width": w, "height": h})
        page.evaluate(NEXT_FRAME)  # laid out and painted at the new size
        shot(page, f"camera-{name}-{w}")
        _axe_clean(page)
        overflow = page.evaluate("document.documentElement.scrollWidth - document.documentElement.clientWidth")
        assert overflow <= 1, f"{name} at {w} px scrolls sideways by {overflow} px"
    page.set_viewport_size({"width": 1366, "height": 900})


def write_constant_y4m(path: Path, luma: int, seconds: float = 2.0) -> Path:
    """Writes a .y4m of one grey level (0 black .. 255 white), 640 x 360 at 30 fps."""
    w, h, n = 640, 360, int(seconds * 30)
    frame = b"FRAME\n" + bytes([luma]) * (w * h) + bytes([128]) * (w * h // 2)
    path.write_bytes(f"YUV4MPEG2 W{w} H{h} F30:1 Ip A1:1 C420jpeg\n".encode() + frame * n)
    return path


@pytest.fixture(scope="module")
def clip(tmp_path_factory) -> Path:
    from tests.fake_camera import sports2d_y4m

    return sports2d_y4m(tmp_path_factory.mktemp("camera") / "sports2d.y4m")


def camera_browser(playwright_module, video: Path | None):
    """Launches headless Chromium whose camera plays `video` (None: no fake device flags)."""
    args = ["--no-sandbox"]
    if video is not None:
        args += ["--use-fake-device-for-media-stream", "--use-fake-ui-for-media-stream",
                 f"--use-file-for-fake-video-capture={video}"]  # fmt: skip
    return playwright_module.chromium.launch(executable_path=CHROMIUM, headless=True, args=args)


@pytest.fixture(scope="module")
def pw(playwright_session):
    """The run's Playwright (tests/frontend/conftest.py), which launches this module's camera browser."""
    return playwright_session


@pytest.fixture(scope="module")
def cam_browser(pw, clip):
    b = camera_browser(pw, clip)
    yield b
    b.close()


def new_patient(base: str, exercise: str = EXERCISE, target: int = TARGET) -> tuple[str, int, int]:
    """Creates a patient with a plan of one exercise (2 sets of target); returns (email, patient id, plan item id)."""
    new = create_patient(base, "cam", "Carla Camera", items=[plan_item(exercise, target)], plan={"title": "Camera"})
    return new.email, new.id, new.item_ids[0]


def patient_sessions(base: str, email: str, pid: int) -> list[dict[str, Any]]:
    with httpx.Client(base_url=base, timeout=30) as c:
        c.post("/api/v1/auth/login", json={"email": email, "password": PASSWORD}).raise_for_status()
        return c.get("/api/v1/sessions", params={"patient_id": pid, "limit": 50}).json()["items"]


def session_header(base: str, email: str, session_id: int):
    with httpx.Client(base_url=base, timeout=60) as c:
        c.post("/api/v1/auth/login", json={"email": email, "password": PASSWORD}).raise_for_status()
        r = c.get(f"/api/v1/sessions/{session_id}/file")
        r.raise_for_status()
        return session_file.decode(r.content)


@contextmanager
def camera_page(browser, base: str) -> Iterator[CheckedPage]:
    """Yields a 1366 x 900 page at base (conftest.open_page) that also keeps the CSP violations in window.__csp
    ([directive, blocked URI] pairs)."""
    with open_page(browser, base, 1366, 900, init_script=WATCH_CSP) as page:
        yield page


@contextmanager
def on_the_consent(browser, base: str) -> Iterator[CheckedPage]:
    """A new patient of new_patient() signed in, on the camera page's consent (its scripts loaded, nothing asked of
    the camera yet): for calling the page's own code."""
    email, _, item_id = new_patient(base)
    with camera_page(browser, base) as page:
        login(page, email, PASSWORD)
        page.wait_for_url("**/patient")
        page.goto(f"{PAGE}?item={item_id}")
        expect(page.locator("#cam-consent")).to_be_visible()
        yield page


def phase(page) -> str:
    return page.locator("#cam-main-status").inner_text()


def wait_phase(page, *names: str, timeout: float = 60_000) -> None:
    """Waits until the page's phase is one of names; on a timeout, fails with where the page is (its phase, its set's
    end step and its sender's queue: CameraPage.state())."""
    script = "(names) => names.includes((document.getElementById('cam-main-status') || {}).textContent)"
    try:
        page.wait_for_function(script, arg=list(names), timeout=timeout)
    except PlaywrightTimeoutError:
        where = page.evaluate("window.CameraPage ? (({ costs, ...s }) => s)(CameraPage.state()) : null")
        raise AssertionError(f"the page is not {' or '.join(names)} after {timeout / 1000:.0f} s: {where}") from None


def test_consent_placement_live_count_and_the_saved_webcam_session(cam_browser, live_server):
    base = live_server.url
    email, pid, item_id = new_patient(base)
    with camera_page(cam_browser, base) as page:
        requested: list[str] = []
        page.on("request", lambda request: requested.append(request.url))
        login(page, email, PASSWORD)
        page.wait_for_url("**/patient")
        start = page.locator("a.cam-start")
        expect(start).to_be_visible()
        expect(start).to_have_text("Start with this computer's camera")
        status = page.locator("#agent-status")  # no home computer: the line names the camera, not a missing computer
        expect(status).to_have_attribute("data-state", "unpaired")
        expect(status).to_have_attribute("data-camera", "")
        label = "Start with this computer's camera"
        words = f"Do your exercises with this computer's camera: press “{label}” next to an exercise."
        expect(status).to_have_text(words)
        shot(page, "camera-patient-start")
        page.goto(f"{PAGE}?item={item_id}&model=lite&delegate=CPU")
        expect(page.locator("#cam-consent")).to_be_visible()
        expect(page.locator("#cam-consent")).to_contain_text("The video never leaves this device")
        expect(page.locator("#cam-consent")).to_contain_text("Only the positions of your joints are sent")
        _shots(page, "consent")
        page.click("#cam-agree")
        wait_phase(page, "placement")
        expect(page.locator("#cam-say")).not_to_be_empty(timeout=60_000)
        page.wait_for_timeout(1500)
        _shots(page, "placement")
        page.evaluate(
            "window.__camCounts = []; addEventListener('coach-camera-count', (e) => __camCounts.push(e.detail))"
        )
        if phase(page) == "placement":
            page.click("#cam-anyway")
        wait_phase(page, "counting")
        expect(page.locator("#cam-count .n")).to_be_visible()
        size = page.evaluate("parseFloat(getComputedStyle(document.querySelector('#cam-count .n')).fontSize)")
        assert size >= 96, f"the live count is {size} px; it must be at least 96 px"
        page.wait_for_function("() => +document.querySelector('#cam-count .n').textContent >= 1", timeout=180_000)
        fps = page.evaluate("CameraPage.state().fps")
        if fps is not None and fps < 10:  # this machine: the page says so, unless it is back to 10 a second (the page
            # says it only after 3 s of counting; a sample in those seconds may be slower than the pace after them)
            page.wait_for_function(SLOW_SAID_OR_FAST, timeout=15_000)
        _shots(page, "counting")
        wait_phase(page, "stored", "failed", timeout=120_000)  # the target ends the set by itself
        assert phase(page) == "stored", page.locator("#cam-result-text").inner_text()
        expect(page.locator("#cam-result-text")).to_contain_text("Saved")
        _shots(page, "result")
        counts = [d["count"] for d in page.evaluate("window.__camCounts")]
        assert counts == sorted(counts) and counts[-1] >= TARGET, counts
        stored = patient_sessions(base, email, pid)
        assert len(stored) == 1 and stored[0]["exercise_slug"] == EXERCISE and stored[0]["device_id"] is None, stored
        # one count (tests/backend/camera/test_camera_count.py): the page's last count is the saved one. The live
        # count before it is evaluated every 0.25 s of recording, so a repetition finished in the set's last moments
        # (the clip goes on through the 1.5 s the page records after the target) is counted only by the saved count,
        # and a flickering label can run the live count ahead (bench/README.md, "Webcam counts"); a page on a loaded
        # machine may see too few pictures of a repetition. A change is said, never made silently.
        shown = page.evaluate("CameraPage.state().count")
        saved = stored[0]["repetitions"]
        assert saved == shown, (saved, shown, counts)
        _says_the_recount(page, counts[-1], saved)
        if saved is not None and saved < TARGET:  # the live count reached the goal, the saved one did not
            expect(page.locator("#cam-result-more")).not_to_contain_text("You reached your goal")
        # how it felt, asked under the result as after a set of the home computer (issue 23 point 4)
        feeling = page.locator("#cam-feeling #feeling")
        expect(feeling).to_be_visible()
        feeling.locator("#feeling-effort").get_by_role("button", name="5", exact=True).click()
        feeling.locator("#feeling-save").click()
        expect(page.locator("#cam-feeling #feeling-thanks")).to_contain_text("Thank you")
        said = page.context.request.get(f"/api/v1/sessions/{stored[0]['id']}/feeling").json()
        assert (said["pain"], said["effort"]) == (None, 5.0), said
        payload = session_header(base, email, stored[0]["id"])
        assert payload.raw.meta.device == "webcam", payload.raw.meta
        assert (
            payload.params["model"]["name"] == "pose_landmarker_lite.task"
            and len(payload.params["model"]["sha256"]) == 64
        )
        assert payload.params["fps_achieved"] and payload.params["fps_achieved"] > 1, payload.params
        off_origin = [u for u in requested if not u.startswith(base) and not u.startswith(("data:", "blob:"))]
        assert not off_origin, off_origin
        # the WebAssembly compiled under the page's CSP; only connections off the origin (MediaPipe's metrics) may be
        # refused by it
        violations = page.evaluate("window.__csp")
        assert all(d == "connect-src" and not u.startswith(base) for d, u in violations), violations
        assert not page.js_errors, page.js_errors


def _says_the_recount(page, live: int, saved: int) -> None:
    """Holds that the result says the saved count differs from the last live one when it does, and only then.

    How far apart they may be on this clip is not held here: its one squat-like crouch per pass is counted 0 to 2
    times live as labels flicker (CI and this machine, 2026-11-27: live 2 saved 0 at 2 pictures a second, live 4 saved
    2 at 12), the open point of issue 22; tests/backend/camera/test_camera_count.py holds the live and saved counts
    together on sets of known counts."""
    more = page.locator("#cam-result-more").inner_text()
    said = f"While you exercised we counted {live}. Counted again over the whole set, it is {saved}."
    assert (said in more) == (live != saved) and ("counted" in more) == (live != saved), (live, saved, more)


def _start_counting(page, item_id: int, agree: bool = True) -> None:
    """Opens the camera page of a plan item with the lite model, agrees (agree), skips the placement check: counting."""
    page.goto(f"{PAGE}?item={item_id}&model=lite&delegate=CPU")
    if agree:
        page.click("#cam-agree")
    wait_phase(page, "placement")
    page.click("#cam-anyway")
    wait_phase(page, "counting")


def _to_counting(page, item_id: int, agree: bool = True) -> str:
    _start_counting(page, item_id, agree)
    page.wait_for_function("() => CameraPage.state().next_seq >= 3", timeout=60_000)
    return page.evaluate("CameraPage.state().set_id")


def test_hidden_tab_network_loss_reload_and_unplugged_camera_mid_set_store_one_session(cam_browser, live_server):
    base = live_server.url
    email, pid, item_id = new_patient(base, target=50)  # a set that does not end by itself
    with camera_page(cam_browser, base) as page:
        status = page.locator("#cam-status")
        login(page, email, PASSWORD)
        page.wait_for_url("**/patient")
        set_id = _to_counting(page, item_id)
        # tab hidden (or the laptop asleep), then back
        page.evaluate("Object.defineProperty(document, 'hidden', {value: true, configurable: true});"
                      "document.dispatchEvent(new Event('visibilitychange'))")  # fmt: skip
        expect(status).to_contain_text("paused because this page was hidden")
        page.evaluate("Object.defineProperty(document, 'hidden', {value: false, configurable: true});"
                      "document.dispatchEvent(new Event('visibilitychange'))")  # fmt: skip
        expect(status).to_contain_text("Welcome back")
        # the network lost mid-set, then back: batches wait in IndexedDB and go out in order
        page.context.set_offline(True)
        expect(status).to_contain_text("connection to the server is lost", timeout=20_000)
        shot(page, "camera-offline")
        _axe_clean(page)
        # a batch made while offline is kept (IndexedDB) until the network is back
        deadline = time.monotonic() + 20
        while (kept := page.evaluate(KEPT_BATCHES)) < 1 and time.monotonic() < deadline:
            page.wait_for_timeout(100)  # IndexedDB is asked again (wait_for_function does not await a promise)
        assert kept >= 1, "no batch was kept while offline"
        page.context.set_offline(False)
        expect(status).to_contain_text("The connection is back", timeout=30_000)
        # the page reloaded mid-set: the set is offered to go on, with the same id
        page.reload()
        expect(page.locator("#cam-resume")).to_be_visible()
        expect(page.locator("#cam-resume-text")).to_contain_text("We kept")
        shot(page, "camera-resume")
        _axe_clean(page)
        page.click("#cam-continue")
        wait_phase(page, "placement")
        page.click("#cam-anyway")
        wait_phase(page, "counting")
        assert page.evaluate("CameraPage.state().set_id") == set_id
        # poses sent after the reload, and as many as a set needs to be stored, whatever pace this machine gives: in CI
        # (3 passes on 2 cores) the landmarker saw 1-2 pictures a second, so 3 batches were 1 frame each and the set
        # too short to save (a count of batches stood in for a count of frames)
        page.wait_for_function(
            "(n) => CameraPage.state().frames >= 3 && CameraPage.state().received >= n",
            arg=limits.MIN_END_FRAMES,
            timeout=180_000,
        )
        received = page.evaluate("CameraPage.state().received")
        # the camera unplugged mid-set: said in words; what was done is saved on request
        page.evaluate(
            "document.getElementById('cam-video').srcObject.getVideoTracks()[0].dispatchEvent(new Event('ended'))"
        )
        expect(page.locator("#cam-problem-text")).to_contain_text("camera was disconnected")
        expect(page.locator("#cam-problem-h")).to_have_text("The camera stopped")  # it had started
        shot(page, "camera-unplugged")
        _axe_clean(page)
        page.click("#cam-problem-save")
        wait_phase(page, "stored", "failed", timeout=120_000)
        assert phase(page) == "stored", page.locator("#cam-result-text").inner_text()
        stored = patient_sessions(base, email, pid)
        assert len(stored) == 1 and stored[0]["client_session_id"] == set_id, stored
        assert stored[0]["n_frames"] >= received, (stored, received)
        assert page.evaluate("(id) => CameraBuffer.batches(id).then((b) => b.length)", set_id) == 0
        assert not page.js_errors, page.js_errors


@pytest.mark.parametrize(
    ("flags", "says"),
    [
        (["--use-fake-device-for-media-stream"], "did not allow this page to use the camera"),  # no permission
        (["--use-fake-ui-for-media-stream"], "could not find a camera"),  # no camera at all
    ],
    ids=["permission-denied", "no-camera"],
)
def test_a_camera_that_cannot_start_is_said_in_plain_words(pw, live_server, flags, says):
    base = live_server.url
    email, _, item_id = new_patient(base)
    b = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=["--no-sandbox", *flags])
    with closing(b), camera_page(b, base) as page:
        login(page, email, PASSWORD)
        page.wait_for_url("**/patient")
        if "could not find" in says:
            expect(page.locator("a.cam-start")).to_be_hidden()  # no camera: the patient page offers none
            expect(page.locator("#agent-status")).to_contain_text("No home computer is set up for you yet")
        page.goto(f"{PAGE}?item={item_id}&model=lite&delegate=CPU")
        page.click("#cam-agree")
        expect(page.locator("#cam-problem-text")).to_contain_text(says)
        expect(page.locator("#cam-problem-h")).to_have_text("The camera cannot start")
        expect(page.locator("#cam-retry")).to_be_visible()
        shot(page, f"camera-problem-{'denied' if 'allow' in says else 'none'}")
        _axe_clean(page)


@pytest.mark.parametrize(("luma", "code"), [(5, "dark"), (128, "nobody")], ids=["dark", "nobody"])
def test_a_dark_picture_and_an_empty_one_are_named_in_the_placement_check(pw, live_server, tmp_path, luma, code):
    base = live_server.url
    email, _, item_id = new_patient(base)
    b = camera_browser(pw, write_constant_y4m(tmp_path / f"grey{luma}.y4m", luma))
    with closing(b), camera_page(b, base) as page:
        login(page, email, PASSWORD)
        page.wait_for_url("**/patient")
        page.goto(f"{PAGE}?item={item_id}&model=lite&delegate=CPU")
        page.click("#cam-agree")
        wait_phase(page, "placement")
        page.wait_for_function("(c) => document.getElementById('cam-say').dataset.code === c", arg=code, timeout=60_000)
        text = page.locator("#cam-say").inner_text()
        assert ("too dark" in text) if code == "dark" else ("cannot see you" in text), text


def test_two_people_and_the_patient_kept_in_the_checks(cam_browser, live_server):
    """The placement and tracking rules on landmarks of two people (the page's own functions in Chromium)."""
    from tests.backend.camera.landmarks import body, image_of

    world = body()
    me = [{"x": x, "y": y, "z": z, "visibility": 0.95} for x, y, z in image_of(world)]
    other = [dict(p, x=p["x"] + 0.4) for p in me]
    w = [{"x": x, "y": y, "z": z} for x, y, z in world]
    with on_the_consent(cam_browser, live_server.url) as page:
        out = page.evaluate(
            """([me, other, w]) => {
                const ex = {plane: "frontal", defining_angles: ["shoulder_abduction_L"]};
                const c = (image, count) => CameraChecks.placement({image, world: w, count, luma: 120, ex}).code;
                const prev = CameraChecks.centre(me);
                const dark = CameraChecks.placement({image: me, world: w, count: 1, luma: 10, ex}).code;
                return {two: c(me, 2), one: c(me, 1), nobody: c(null, 0), dark,
                        kept: CameraChecks.pick({landmarks: [other, me]}, prev),
                        onlyOther: CameraChecks.pick({landmarks: [other]}, prev),
                        side: CameraChecks.viewFor({plane: "sagittal", defining_angles: ["knee_flexion_L"]}),
                        front: CameraChecks.viewFor({plane: "sagittal", defining_angles: ["elbow_flexion_L"]})};
            }""",
            [me, other, w],
        )
        assert out == {"two": "two_people", "one": "ok", "nobody": "nobody", "dark": "dark", "kept": 1,
                       "onlyOther": -1, "side": "side", "front": "front"}, out  # fmt: skip


def _placement_cases() -> dict[str, list[Any]]:
    """Landmark frames (image, world) of one person for each instruction of the placement check: the body of
    tests/backend/camera/landmarks.py facing the camera (front), turned sideways (side), scaled about its middle
    (close, far: the needed landmarks' vertical span 0.94 and 0.3 of the picture, centred), shifted right (off
    centre), its ankles below the picture and its wrists unseen."""
    from tests.backend.camera.landmarks import body, image_of

    world = body()
    side = world[:, [2, 1, 0]]  # turned 90 degrees: the shoulders' line along the camera's axis
    img = image_of(world)
    legs = [0, 11, 12, 23, 24, 25, 26, 27, 28]
    lo, hi = img[legs, 1].min(), img[legs, 1].max()

    def scaled(span: float):
        out = img.copy()
        out[:, 1] = 0.5 + (img[:, 1] - (lo + hi) / 2) * span / (hi - lo)
        return out

    def pts(a, vis: float = 0.95, low_vis: tuple[int, ...] = ()):
        return [{"x": x, "y": y, "z": z, "visibility": 0.1 if i in low_vis else vis} for i, (x, y, z) in enumerate(a)]

    shifted, ankles_out = img.copy(), img.copy()
    shifted[:, 0] += 0.35
    ankles_out[[27, 28, 29, 30, 31, 32], 1] = 1.05
    w = lambda a: [{"x": x, "y": y, "z": z} for x, y, z in a]  # noqa: E731
    return {"front": [pts(img), w(world)], "side": [pts(img), w(side)], "close": [pts(scaled(0.94)), w(world)],
            "far": [pts(scaled(0.3)), w(world)], "off": [pts(shifted), w(world)],
            "ankles": [pts(ankles_out), w(world)], "wrists": [pts(img, low_vis=(15, 16)), w(world)]}  # fmt: skip


def test_each_placement_instruction_is_given_for_its_pose(cam_browser, live_server):
    """The placement check's instructions (the page's own CameraChecks.placement in Chromium, the patient's language
    catalogue): whole body or upper body in view, too close, too far, side view for a squat, front view for a
    shoulder abduction, off centre, and "hold still" once the pose is right."""
    with on_the_consent(cam_browser, live_server.url) as page:
        out = page.evaluate(
            """(cases) => {
                const squat = {plane: "sagittal", defining_angles: ["knee_flexion_L", "knee_flexion_R"]};
                const arms = {plane: "frontal", defining_angles: ["shoulder_abduction_L", "shoulder_abduction_R"]};
                const c = (name, ex) => {
                    const [image, world] = cases[name];
                    const r = CameraChecks.placement({image, world, count: 1, luma: 120, ex});
                    return [r.code, r.ok, r.say];
                };
                return {ankles: c("ankles", squat), wrists: c("wrists", arms), close: c("close", squat),
                        far: c("far", squat), squat_front: c("front", squat), squat_side: c("side", squat),
                        arms_side: c("side", arms), arms_front: c("front", arms), off: c("off", arms)};
            }""",
            _placement_cases(),
        )
        assert out == {
            "ankles": ["out_of_view", False, "Step back until your whole body is in the picture, from head to feet."],
            "wrists": ["out_of_view", False, "Step back until your head, arms and hips are in the picture."],
            "close": ["too_close", False, "Step back a little."],
            "far": ["too_far", False, "Come a little closer to the camera."],
            "squat_front": ["view", False, "Please turn sideways to the camera, so it sees you from the side."],
            "squat_side": ["ok", True, "Good! Hold still for a moment…"],
            "arms_side": ["view", False, "Please face the camera."],
            "arms_front": ["ok", True, "Good! Hold still for a moment…"],
            "off": ["off_centre", False, "Move to the middle of the picture."],
        }, out


def test_the_result_says_the_goal_was_reached_only_when_the_saved_count_reaches_it(cam_browser, live_server):
    """The result's sentence after a set the live count ended at its target (CameraText.resultMore): "You reached your
    goal" only when the saved count reaches the target too; when the whole set's count is lower, the recount is said
    instead (seen on this machine: "Saved: 1 of 2 repetitions" above "You reached your goal. While you exercised we
    counted 4. Counted again over the whole set, it is 1.")."""
    with on_the_consent(cam_browser, live_server.url) as page:
        said = page.evaluate(
            """() => ({short: CameraText.resultMore("target", 4, 1, 2, 22.4),
                       met: CameraText.resultMore("target", 2, 2, 2, null),
                       more: CameraText.resultMore("target", 2, 3, 2, null),
                       stop: CameraText.resultMore("stop", 1, 1, 2, 30),
                       uncounted: CameraText.resultMore("target", 2, null, 2, null)})"""
        )
        recount = "While you exercised we counted 4. Counted again over the whole set, it is 1."
        assert said == {
            "short": f"{recount} You moved through 22 degrees.",
            "met": "You reached your goal.",
            "more": "You reached your goal. While you exercised we counted 2. Counted again over the whole set, "
            "it is 3.",
            "stop": "You stopped the set. You moved through 30 degrees.",
            "uncounted": "",
        }, said


def test_the_camera_set_speaks_the_patient_language(pw, live_server):
    """A German patient: the patient page's camera link, the consent screen (390 px, axe-clean, no English left) and
    a fault message (the browser refused the camera) all in German."""
    base = live_server.url
    email, pid, item_id = new_patient(base)
    admin, headers = api_client(base, "admin@demo.clinic")
    try:
        r = admin.patch(f"/api/v1/patients/{pid}", json={"locale": "de"}, headers=headers)
        assert r.status_code == 200, r.text
    finally:
        admin.close()
    b = pw.chromium.launch(executable_path=CHROMIUM, headless=True,
                           args=["--no-sandbox", "--use-fake-device-for-media-stream"])  # fmt: skip
    with closing(b), camera_page(b, base) as page:
        login(page, email, PASSWORD)
        page.wait_for_url("**/patient")
        start = page.locator("a.cam-start")
        expect(start).to_have_text("Mit der Kamera dieses Computers beginnen")
        expect(start).to_have_attribute(
            "aria-label", re.compile(r"^Mit der Kamera dieses Computers beginnen: .+, Satz 1 von 2$")
        )
        page.set_viewport_size({"width": 390, "height": 844})
        page.goto(f"{PAGE}?item={item_id}&model=lite&delegate=CPU")
        consent = page.locator("#cam-consent")
        expect(consent).to_be_visible()
        expect(consent).to_contain_text("Das Video bleibt auf diesem Gerät.")
        expect(page.locator("#cam-status")).to_have_text("Bitte lesen Sie das zuerst.")
        assert page.get_attribute("html", "lang") == "de"
        text = page.inner_text("body")
        english = ("The video never leaves", "Only the positions", "Before you start", "I agree", "Not now",
                   "Please read this first", "Withdraw")  # fmt: skip
        assert not [e for e in english if e in text], text
        shot(page, "camera-consent-de-390")
        _axe_clean(page)
        overflow = page.evaluate("document.documentElement.scrollWidth - document.documentElement.clientWidth")
        assert overflow <= 1, f"the German consent screen scrolls sideways by {overflow} px"
        page.click("#cam-agree")
        expect(page.locator("#cam-problem-text")).to_contain_text(
            "Der Browser hat dieser Seite die Kamera nicht erlaubt"
        )
        expect(page.locator("#cam-retry")).to_have_text("Noch einmal versuchen")
        shot(page, "camera-problem-de-390")
        assert not page.js_errors, page.js_errors


def test_the_patient_leaving_the_picture_mid_set_is_told_and_back_in_view_counting_goes_on(pw, live_server, tmp_path):
    """The camera shows the patient for 4 s, then an empty room for 4 s, in a loop: mid-set the page says "You left
    the picture" once nobody was followed for 1.5 s (camera_page.js LOST_MS), and stops saying it when the patient is
    back in view (the set goes on: frames are sent again)."""
    from tests.fake_camera import append_blank, sports2d_y4m

    base = live_server.url
    email, _, item_id = new_patient(base, target=50)  # a set that does not end by itself
    video = append_blank(sports2d_y4m(tmp_path / "leaves.y4m", start_s=0.0, seconds=4.0), 4.0)
    b = camera_browser(pw, video)
    with closing(b), camera_page(b, base) as page:
        say = page.locator("#cam-say")
        login(page, email, PASSWORD)
        page.wait_for_url("**/patient")
        _start_counting(page, item_id)
        expect(say).to_contain_text("You left the picture", timeout=60_000)
        assert say.get_attribute("data-level") == "warn"
        shot(page, "camera-left-picture")
        _axe_clean(page)
        seq = page.evaluate("CameraPage.state().next_seq")
        expect(say).not_to_contain_text("You left the picture", timeout=60_000)  # back in view
        page.wait_for_function("(s) => CameraPage.state().next_seq > s", arg=seq, timeout=60_000)
        assert phase(page) == "counting"
        assert not page.js_errors, page.js_errors


def test_a_camera_slower_than_10_frames_a_second_is_said_mid_set(pw, live_server, tmp_path):
    """A camera that gives 4 frames a second (the fake camera's clip at 4 fps, whatever this machine's speed): after
    3 s of counting the page says the computer is slow, and the rate it measured is the camera's."""
    from tests.fake_camera import sports2d_y4m

    base = live_server.url
    email, _, item_id = new_patient(base, target=50)
    b = camera_browser(pw, sports2d_y4m(tmp_path / "slow.y4m", fps=4, start_s=0.0, seconds=5.0))
    with closing(b), camera_page(b, base) as page:
        note = page.locator("#cam-note")
        login(page, email, PASSWORD)
        page.wait_for_url("**/patient")
        _start_counting(page, item_id)
        expect(note).to_have_text("This computer is slow, so counting may be less exact.", timeout=60_000)
        fps = page.evaluate("CameraPage.state().fps")
        # the camera's pace, not the landmarker's (12-16 a second here): Chromium's fake camera gives the 4 fps clip's
        # frames at 4-8 distinct frames a second depending on the machine's load
        assert fps is not None and fps < 10.0, fps
        shot(page, "camera-slow")
        _axe_clean(page)
        assert not page.js_errors, page.js_errors


def test_a_slow_computer_on_the_full_model_is_switched_to_the_lite_one_and_told(pw, live_server, tmp_path):
    """A computer the page gives the full model (4 cores or more, no ?model=) whose pictures come at 4 a second: after
    3 s of the placement check the page loads the lite model, says so, and goes on with the check."""
    from tests.fake_camera import sports2d_y4m

    base = live_server.url
    email, _, item_id = new_patient(base, target=50)
    b = camera_browser(pw, sports2d_y4m(tmp_path / "slow.y4m", fps=4, start_s=0.0, seconds=5.0))
    with closing(b), camera_page(b, base) as page:
        page.add_init_script("Object.defineProperty(navigator, 'hardwareConcurrency', {get: () => 8})")
        login(page, email, PASSWORD)
        page.wait_for_url("**/patient")
        page.goto(f"{PAGE}?item={item_id}&delegate=CPU")
        page.click("#cam-agree")
        wait_phase(page, "placement")
        assert page.evaluate("CameraPose.info.model") == "full"
        expect(page.locator("#cam-note")).to_have_text(
            "This computer is slow, so we switched to a lighter movement tracker.", timeout=90_000
        )
        wait_phase(page, "placement")
        assert page.evaluate("CameraPose.info.model") == "lite"
        expect(page.locator("#cam-say")).not_to_be_empty(timeout=60_000)
        assert not page.js_errors, page.js_errors


DYING_WORKER = """import { load, detect } from "./camera_pose_core.js";
let detections = 0;
self.onmessage = async ({ data }) => {
  if (data.type === "load") self.postMessage(await load(data));
  else if (++detections > 30) self.close();  // gone without a word, as a worker the browser killed
  else self.postMessage(await detect(data));
};"""


@pytest.mark.parametrize("how", ["cannot-start", "dies-mid-set"])
def test_the_landmarker_runs_on_the_page_when_its_worker_cannot_start_or_dies(cam_browser, live_server, how):
    """A browser that cannot start the landmarker's module worker (here its script does not load; in the field:
    Firefox before 114, Safari before 15), or whose worker goes silent mid-set (here it closes itself after 30
    frames, before the first repetition): the page runs the landmarker itself, sends its poses, counts them and
    stores the set."""
    base = live_server.url
    email, pid, item_id = new_patient(base, target=50)  # a set that does not end by itself: the test stops it
    with camera_page(cam_browser, base) as page:
        warnings: list[str] = []
        page.on("console", lambda msg: warnings.append(msg.text) if msg.type == "warning" else None)
        if how == "cannot-start":
            page.route("**/static/camera_pose_worker.js", lambda route: route.abort())
        else:
            page.route("**/static/camera_pose_worker.js",
                       lambda route: route.fulfill(response=route.fetch(), body=DYING_WORKER))  # fmt: skip
        page.add_init_script(
            "window.__camCounts = []; addEventListener('coach-camera-count', (e) => __camCounts.push(e.detail.count))"
        )
        login(page, email, PASSWORD)
        page.wait_for_url("**/patient")
        _start_counting(page, item_id)
        page.wait_for_function("() => CameraPage.state().model.where === 'page'", timeout=60_000)
        said = "gave no answer in 8000 ms" if how == "dies-mid-set" else "the pose landmarker runs on the page"
        assert any(said in w for w in warnings), warnings
        # The patient stops once the page's landmarker has sent 31 poses (frames, whatever the batches: a loaded
        # machine's page sees 1-2 pictures a second, an idle one 15). The set must still be counting then: the time the
        # landmarker took to start on the page (46 s on a loaded machine) is not "standing still" (it ended the set
        # as still on the page's first batch: kinect_agent/analysis/live.py, GAP_S).
        sent = page.evaluate("CameraPage.state().frames")
        sent_or_ended = "(s) => CameraPage.state().phase !== 'counting' || CameraPage.state().frames >= s + 31"
        page.wait_for_function(sent_or_ended, arg=sent, timeout=240_000)
        assert phase(page) == "counting", page.evaluate("CameraPage.state()")
        page.click("#cam-stop")
        # the page's landmarker shares the main thread with the set's end; a whole run at load 16 took over 120 s
        wait_phase(page, "stored", "failed", timeout=240_000)
        assert phase(page) == "stored", page.locator("#cam-result-text").inner_text()
        # What must hold: the page's own poses reached the server (the dying worker answers 30 frames at most, so a
        # stored frame beyond 30 is the page's), the page's last count is the stored one, and a recount is said.
        expect(page.locator("#cam-result-text")).to_contain_text(re.compile(r"Saved: (all )?\d+"))
        live = page.evaluate("window.__camCounts")
        stored = patient_sessions(base, email, pid)
        assert len(stored) == 1 and stored[0]["n_frames"] > 30, stored
        assert stored[0]["n_frames"] == page.evaluate("CameraPage.state().frames"), stored  # every pose sent is kept
        assert len(stored) == 1 and stored[0]["repetitions"] == page.evaluate("CameraPage.state().count"), stored
        assert live
        _says_the_recount(page, live[-1], stored[0]["repetitions"])
        assert not page.js_errors, page.js_errors


WATCH_CODES = ("window.__codes = new Set(); new MutationObserver(() => __codes.add(document.getElementById('cam-say')"
               ".dataset.code)).observe(document, {subtree: true, attributes: true, "
               "attributeFilter: ['data-code']})")  # fmt: skip


@pytest.mark.parametrize("scene", ["two-people", "alone"])
def test_a_second_person_is_seen_and_one_person_alone_is_tracked_cheaply(pw, live_server, tmp_path, scene):
    """The landmarker's company watch (camera_pose_core.js): with two people in view (Pose2Sim's two-person demo,
    tests/fake_camera.py two_people_y4m) the placement check says "someone else is in the picture" and the landmarker
    that looks for two people answers; with one person in view (Sports2D's walker below the hut, cropped) the single
    tracker answers most frames (it does not run the person detector on every frame: bench/README.md). Looking for
    a second person only on the single tracker's frames, or never, fails the first case."""
    from tests.fake_camera import sports2d_y4m, two_people_y4m

    base = live_server.url
    email, _, item_id = new_patient(base, target=50)
    if scene == "two-people":
        video = two_people_y4m(tmp_path / "two.y4m")
    else:  # the walker's strip below the hut's roof: one person in view, then nobody
        video = sports2d_y4m(tmp_path / "alone.y4m", crop=(0.0, 0.47, 1.0, 1.0))
    b = camera_browser(pw, video)
    with closing(b), camera_page(b, base) as page:
        page.add_init_script(WATCH_CODES)
        login(page, email, PASSWORD)
        page.wait_for_url("**/patient")
        page.goto(f"{PAGE}?item={item_id}&model=lite&delegate=CPU")
        page.click("#cam-agree")
        wait_phase(page, "placement")
        if scene == "two-people":
            page.wait_for_function("() => window.__codes.has('two_people')", timeout=90_000)
            expect(page.locator("#cam-say")).to_be_visible()
            by = page.evaluate("CameraPage.state().by")
            assert by["two"] > 0, by
        else:
            # most of 150 frames, not of fewer: a look that takes something for a second person hands about a second
            # of frames to `two` (ALONE_MS), 23 of the first 60 once at 16 frames a second; over 150 frames `one`
            # answered 85 % idle and 67 % (101 of 151) in a whole run's load. A landmarker looking for two on every
            # frame (no watch) answers none by `one`.
            frames = "() => CameraPage.state().by.one + CameraPage.state().by.two >= 150"
            page.wait_for_function(frames, timeout=180_000)
            by = page.evaluate("CameraPage.state().by")
            assert by["one"] > by["two"], by
        assert not page.js_errors, page.js_errors
