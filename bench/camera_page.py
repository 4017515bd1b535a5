"""The camera page in headless Chromium on this machine: the pose landmarker's frame rate (lite and full model, CPU
delegate: no GPU here) and the time from a frame captured to its count on the patient's screen.

Starts the real app (uvicorn, SQLite in a temp folder, migrated, the demo clinic seeded) on --port, launches
Chromium with Sports2D's demo video (PyPI `sports2d` 0.8.34, BSD-3-Clause; tests/fake_camera.py) as its camera,
signs in as the demo's camera patient and opens /patient/camera for her squat. For each model and run: the
placement check runs --seconds; the landmarker's rate is the page's own (frames detected over its last 3 s,
sampled each second, median). Then (lite only) "Start anyway" and --seconds of counting: for each batch answer,
the page reports how long ago its oldest and its newest frame were captured (Date.now() before the landmarker ran,
to the count drawn): `oldest` includes the 0.1 s batching, `newest` the landmarker, network and server only.

    python bench/camera_page.py [--runs 3] [--seconds 15] [--port 8102] [--models lite full]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from playwright.sync_api import Browser, Page

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import httpx  # noqa: E402

from backend.demo import CAMERA_PATIENT, DEMO_PASSWORD  # noqa: E402
from bench.dashboard_load import percentile, start_server, stop_server  # noqa: E402

CHROMIUM = "/usr/bin/chromium"
# what the page reports per answer (camera_page.js onAnswer): the whole, then its parts for the newest frame
# the page's timing of each frame (camera_page.js cost()): the landmarker idle before it, the grab, the round trip to
# the worker, the detection in the worker, the page's handling of the answer
COST_PARTS = ("idle_ms", "grab_ms", "trip_ms", "detect_ms", "page_ms")
PARTS = ("newest_ms", "oldest_ms", "landmarker_ms", "buffer_ms", "server_ms", "draw_ms")


def prepare(db_url: str) -> None:
    env = {**os.environ, "COACH_DATABASE_URL": db_url, "COACH_ENVIRONMENT": "local"}
    for step in ("migrate", "seed-demo"):
        subprocess.run([str(Path(sys.executable).parent / "coach-server"), step], env=env, check=True, cwd=ROOT,
                       stdout=subprocess.DEVNULL)  # fmt: skip


def squat_item(base: str) -> int:
    with httpx.Client(base_url=base, timeout=30) as c:
        me = c.post("/api/v1/auth/login", json={"email": CAMERA_PATIENT[0], "password": DEMO_PASSWORD}).json()
        plans = c.get(f"/api/v1/patients/{me['user']['id']}/plans").json()["items"]
    return next(i["id"] for p in plans for i in p["items"] if i["exercise_slug"] == "squat")


def to_placement(page: Page, item: int, model: str) -> None:
    """Signs in as the demo's camera patient and opens the camera page of plan item `item` with `model` on the CPU
    delegate, consenting if asked; returns once its placement check runs (the camera is open)."""
    page.goto("/")
    page.fill("#email", CAMERA_PATIENT[0])
    page.fill("#password", DEMO_PASSWORD)
    page.click("#login-submit")
    page.wait_for_url("**/patient")
    page.goto(f"/patient/camera?item={item}&model={model}&delegate=CPU")
    page.wait_for_function("() => ['consent', 'placement'].includes(document.getElementById('cam-main-status')"
                           "?.textContent)")  # fmt: skip
    if page.locator("#cam-main-status").inner_text() == "consent":
        page.click("#cam-agree")
    page.wait_for_function("() => document.getElementById('cam-main-status').textContent === 'placement'")


def one_run(browser: Browser, base: str, item: int, model: str, seconds: float, count: bool) -> dict[str, Any]:
    context = browser.new_context(viewport={"width": 1366, "height": 900}, base_url=base)
    page = context.new_page()
    page.set_default_timeout(120_000)
    try:
        to_placement(page, item, model)
        page.wait_for_timeout(4000)  # warm-up: the first frames compile and allocate
        rates = []
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            page.wait_for_timeout(1000)
            fps = page.evaluate("CameraPage.state().fps")
            if fps:
                rates.append(fps)
        out = {"fps": statistics.median(rates) if rates else float("nan"), "delegate": page.evaluate(
            "CameraPage.state().model.delegate"), "costs": page.evaluate("CameraPage.state().costs")}  # fmt: skip
        if count:
            page.evaluate("window.__lat = []; addEventListener('coach-camera-count', (e) => __lat.push(e.detail))")
            page.click("#cam-anyway")
            page.wait_for_function("() => document.getElementById('cam-main-status').textContent === 'counting'")
            page.wait_for_timeout(seconds * 1000)
            lat = page.evaluate("window.__lat")
            for key in PARTS:
                out[key] = [d[key] for d in lat if d.get(key) is not None]
            if page.locator("#cam-stop").is_visible():
                page.click("#cam-stop")
            page.wait_for_function("() => ['stored', 'failed'].includes(document.getElementById('cam-main-status')"
                                   ".textContent)")  # fmt: skip
        return out
    finally:
        context.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=15.0)
    parser.add_argument("--port", type=int, default=8102)
    parser.add_argument("--models", nargs="+", default=["lite", "full"], choices=["lite", "full"])
    args = parser.parse_args(argv)
    from playwright.sync_api import sync_playwright

    from tests.fake_camera import sports2d_y4m

    with tempfile.TemporaryDirectory() as tmp:
        clip = sports2d_y4m(Path(tmp) / "sports2d.y4m")
        db_url = f"sqlite:///{tmp}/bench.db"
        prepare(db_url)
        server = start_server(db_url, args.port, 1)
        base = f"http://127.0.0.1:{args.port}"
        try:
            item = squat_item(base)
            with sync_playwright() as pw:
                browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=[
                    "--no-sandbox", "--use-fake-device-for-media-stream", "--use-fake-ui-for-media-stream",
                    f"--use-file-for-fake-video-capture={clip}"])  # fmt: skip
                results: dict[str, list[dict[str, Any]]] = {m: [] for m in args.models}
                for r in range(args.runs):
                    for model in args.models:
                        res = one_run(browser, base, item, model, args.seconds, count=model == "lite")
                        results[model].append(res)
                        answers = f", {len(res['newest_ms'])} answers" if "newest_ms" in res else ""
                        print(f"run {r + 1} {model}: {res['fps']:.1f} fps ({res['delegate']}){answers}", flush=True)
                browser.close()
        finally:
            stop_server(server)
    cores = os.cpu_count()
    load = os.getloadavg()[0]
    print(f"\nheadless Chromium, CPU delegate, {cores} cores, load average {load:.1f} at the end")
    for model, runs in results.items():
        fps = [r["fps"] for r in runs]
        print(f"  {model}: landmarker {statistics.median(fps):.1f} fps median of {len(fps)} runs "
              f"({', '.join(f'{v:.1f}' for v in fps)})")  # fmt: skip
    for model, runs in results.items():  # where each frame's time went during the placement check
        rows = [c for r in runs for c in r["costs"]]
        if rows:
            parts = ", ".join(f"{k[:-3]} {statistics.median(c[k] or 0 for c in rows):.1f} / "
                              f"{statistics.fmean(c[k] or 0 for c in rows):.1f}" for k in COST_PARTS)  # fmt: skip
            looks = [c["look_ms"] for c in rows if c.get("look_ms")]
            spike = f"; `two`'s looks {len(looks)}, p50 {statistics.median(looks):.0f} ms" if looks else ""
            print(f"  {model} per frame, median / mean ms over {len(rows)} frames: {parts}{spike}")
    lite = results.get("lite", [])
    for key in PARTS:
        values = [v for r in lite for v in r.get(key, [])]
        if values:
            p95s = [percentile(r[key], 95) for r in lite if r.get(key)]
            what = f"frame -> count ({key.split('_')[0]} frame of a batch)" if key in PARTS[:2] else f"  {key[:-3]}"
            print(f"  {what}: p50 {percentile(values, 50):.0f} ms, "
                  f"p95 {percentile(values, 95):.0f} ms over {len(values)} answers; p95 per run "
                  f"{', '.join(f'{v:.0f}' for v in p95s)}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
