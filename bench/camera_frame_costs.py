"""Where a camera frame's time goes in headless Chromium on this machine (issue 22), in three parts:

(a) the landmarker alone: the app's worker (frontend/static/camera_pose_worker.js), no page work, fed the camera
    tests' clip (Sports2D's demo, tests/fake_camera.py, 640 x 360) every second frame (15 a second), each frame a
    fresh ImageBitmap; per variant its own worker, variants in alternating blocks so they see the same load. `took` is
    measured inside the worker (camera_pose_core.js: detectForVideo alone), `trip` from postMessage to the answer.
    Variants: `one` (numPoses 1, VIDEO: tracks), the page's watch (`one` + `two`'s look once a second), `one` IMAGE
    (the person detector on every frame), and `one` fed frames downscaled to --widths before the worker (the model's
    input is 256 x 256 anyway). Landmarks of each variant against `one` at 640 px on the same frames: median and p95
    of the per-frame median distance of the landmarks seen (visibility > 0.5), in pixels of the 640 x 360 frame.
(b) the page's per-frame work on the real (fake) camera: createImageBitmap(video) at full size and downscaled, and
    new VideoFrame(video), on successive camera frames; the overlay's drawing (CameraPose.draw) with a real pose.
(c) Chromium's own cost of the camera: the browser's CPU time (all its processes, /proc) per second of wall time
    while a page only plays the fake camera, against an idle page; and the camera's frame rate (video frame callbacks).

    python bench/camera_frame_costs.py [--model lite] [--blocks 4] [--block 30] [--widths 480 320] [--skip-a]
"""

from __future__ import annotations

import argparse
import base64
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench.camera_landmarker import ADD_FRAME_JS, FRAME_MS, LOAD_JS, clip_frames  # noqa: E402
from bench.dashboard_load import percentile, start_server, stop_server  # noqa: E402

CHROMIUM = "/usr/bin/chromium"
SEEN = 0.5  # a landmark counts in the accuracy comparison when the reference gives it this visibility

# per frame: [trip ms, took ms (in the worker), look ms, by, people, first person's [x, y, visibility] x 33 or null,
# the copy's ms]
BLOCK_JS = """async ({ name, start, n, frameMs, width }) => {
  const w = window.__workers[name];
  const out = [];
  for (let k = 0; k < n; k++) {
    const src = window.__frames[(start + k) % window.__frames.length];
    const c0 = performance.now();
    const frame = width ? await createImageBitmap(src, { resizeWidth: width,
      resizeHeight: Math.round(width * src.height / src.width), resizeQuality: "low" }) : await createImageBitmap(src);
    const copyMs = performance.now() - c0;
    const id = w.next++;
    w.ms += frameMs;
    const began = performance.now();
    const r = await new Promise((resolve) => {
      w.worker.onmessage = ({ data }) => { if (data.type === "result" && data.id === id) resolve(data.result); };
      w.worker.postMessage({ type: "detect", id, frame, ms: w.ms }, [frame]);
    });
    const first = r && r.landmarks.length ? r.landmarks[0].map((p) => [p.x, p.y, p.visibility]) : null;
    out.push([performance.now() - began, r ? r.took.detect_ms : null, r ? r.took.look_ms : null, r ? r.by : null,
              r ? r.landmarks.length : -1, first, copyMs]);
  }
  return out;
}"""

CAMERA_JS = """async () => {
  const stream = await navigator.mediaDevices.getUserMedia({ audio: false,
    video: { width: { ideal: 640 }, height: { ideal: 480 }, facingMode: "user" } });
  const video = document.createElement("video");
  video.muted = true; video.playsInline = true; video.srcObject = stream;
  document.body.append(video);
  await video.play();
  window.__video = video;
  return [video.videoWidth, video.videoHeight];
}"""

# the camera's frame rate: video frame callbacks over `seconds`
CAMERA_RATE_JS = """async (seconds) => {
  const v = window.__video, t0 = performance.now();
  let n = 0;
  await new Promise((resolve) => {
    const tick = () => {
      n++;
      if (performance.now() - t0 < seconds * 1000) v.requestVideoFrameCallback(tick); else resolve();
    };
    v.requestVideoFrameCallback(tick);
  });
  return n / ((performance.now() - t0) / 1000);
}"""

# the page's grab of a camera frame, each way, on n successive camera frames: ms per call
GRAB_JS = """async ({ n, way, width }) => {
  const v = window.__video, out = [];
  for (let k = 0; k < n; k++) {
    await new Promise((resolve) => v.requestVideoFrameCallback(resolve));
    const t0 = performance.now();
    let f;
    if (way === "bitmap") f = await createImageBitmap(v);
    else if (way === "bitmap-resized") f = await createImageBitmap(v, { resizeWidth: width,
      resizeHeight: Math.round(width * v.videoHeight / v.videoWidth), resizeQuality: "low" });
    else f = new VideoFrame(v, { timestamp: k });
    out.push(performance.now() - t0);
    f.close();
  }
  return out;
}"""

DRAW_JS = """async ({ n, pose }) => {
  if (!window.CameraPose) {
    await new Promise((resolve, reject) => { const s = document.createElement("script");
      s.src = "/static/camera_pose.js"; s.onload = resolve; s.onerror = reject; document.head.append(s); });
  }
  const canvas = document.createElement("canvas");
  document.body.append(canvas);
  const result = { landmarks: [pose.map(([x, y, visibility]) => ({ x, y, z: 0, visibility }))] };
  const out = [];
  for (let k = 0; k < n; k++) {
    await new Promise((resolve) => requestAnimationFrame(resolve));
    const t0 = performance.now();
    CameraPose.draw(canvas, window.__video, result, 0);
    out.push(performance.now() - t0);
  }
  return out;
}"""

RENDERER_JS = """() => {
  const g = new OffscreenCanvas(1, 1).getContext("webgl2");
  if (!g) return "no WebGL 2";
  const e = g.getExtension("WEBGL_debug_renderer_info");
  return e ? g.getParameter(e.UNMASKED_RENDERER_WEBGL) : g.getParameter(g.RENDERER);
}"""


def browser_cpu_s() -> float:
    """Returns the CPU time (user + system, s) of every Chromium process descending from this one (/proc)."""
    tick = os.sysconf("SC_CLK_TCK")
    parent: dict[int, int] = {}
    stats: dict[int, tuple[str, float]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            raw = Path(f"/proc/{entry}/stat").read_text()
            cmd = Path(f"/proc/{entry}/cmdline").read_bytes().split(b"\0")[0].decode(errors="replace")
        except OSError:
            continue
        fields = raw[raw.rindex(")") + 2 :].split()
        parent[int(entry)] = int(fields[1])
        stats[int(entry)] = (cmd, (int(fields[11]) + int(fields[12])) / tick)
    me, total = os.getpid(), 0.0
    for pid, (cmd, cpu) in stats.items():
        p = pid
        while p > 1 and p != me:
            p = parent.get(p, 1)
        if p == me and "chrom" in cmd:
            total += cpu
    return total


def cpu_share(seconds: float, page: Any) -> float:
    """Returns the browser's CPU time per second of wall time over `seconds` (1.0 = one core busy)."""
    c0, t0 = browser_cpu_s(), time.monotonic()
    page.wait_for_timeout(seconds * 1000)
    return (browser_cpu_s() - c0) / (time.monotonic() - t0)


def px_distance(ref: list[Any] | None, other: list[Any] | None, w: int, h: int) -> float | None:
    """Returns the median distance (px of the w x h frame) of the landmarks `ref` sees (visibility > SEEN) between
    two poses ([x, y, visibility] x 33, normalised), or None when either has no pose."""
    if ref is None or other is None:
        return None
    a, b = np.array(ref, dtype=float), np.array(other, dtype=float)
    seen = a[:, 2] > SEEN
    if not seen.any():
        return None
    d = np.hypot((a[seen, 0] - b[seen, 0]) * w, (a[seen, 1] - b[seen, 1]) * h)
    return float(np.median(d))


def part_a(page: Any, args: argparse.Namespace, n_frames: int, w: int, h: int) -> None:
    variants: list[tuple[str, dict[str, Any], int | None]] = [("one 640", {"poses": 1}, None),
        ("watch 640 (the page)", {}, None), ("one 640 IMAGE (detector every frame)", {"poses": 1, "mode": "IMAGE"},
        None)] + [(f"one {v}", {"poses": 1}, v) for v in args.widths]  # fmt: skip
    for name, opts, _ in variants:
        loaded = page.evaluate(LOAD_JS, {"name": name, "model": args.model, **opts})
        assert loaded["type"] == "loaded", loaded
    for name, _, width in variants:  # warm-up: the first frames compile and allocate
        page.evaluate(BLOCK_JS, {"name": name, "start": 0, "n": 8, "frameMs": FRAME_MS, "width": width})
    rows: dict[str, list[list[Any]]] = {name: [] for name, _, _ in variants}
    for b in range(args.blocks):
        order = variants if b % 2 == 0 else variants[::-1]
        for name, _, width in order:
            rows[name] += page.evaluate(BLOCK_JS, {"name": name, "start": (8 + b * args.block) % n_frames,
                                                   "n": args.block, "frameMs": FRAME_MS, "width": width})  # fmt: skip
    print(f"\n(a) the landmarker alone, {args.model}, {args.blocks} blocks of {args.block} frames per variant, load "
          f"{os.getloadavg()[0]:.1f}")  # fmt: skip
    ref = rows["one 640"]
    for name, _, _ in variants:
        r = rows[name]
        took = [x[1] for x in r]
        trip = [x[0] for x in r]
        looks = [x[2] for x in r if x[2]]
        by_one = sum(x[3] == "one" for x in r) / len(r)
        dists = [d for x, y in zip(ref, r, strict=True) if (d := px_distance(x[5], y[5], w, h)) is not None]
        found = sum(x[4] > 0 for x in r)
        line = (f"  {name}: in the worker min {min(took):.1f}, p50 {statistics.median(took):.1f}, mean "
                f"{statistics.fmean(took):.1f}, p95 {percentile(took, 95):.1f} ms; "
                f"trip p50 {statistics.median(trip):.1f} ms ({1000 * len(trip) / sum(trip):.1f} frames/s back to "
                f"back); copy p50 {statistics.median(x[6] for x in r):.1f} ms; a person in {found}/{len(r)}"
                )  # fmt: skip
        if looks:
            line += f"; `two`'s looks {len(looks)}: p50 {statistics.median(looks):.0f} ms, max {max(looks):.0f} ms"
        if by_one < 1 and "watch" in name:
            line += f"; `one` answered {by_one:.0%}"
        if name != "one 640" and dists:
            line += (f"; landmarks vs one 640: median {statistics.median(dists):.2f} px, p95 "
                     f"{percentile(dists, 95):.2f} px ({len(dists)} frames)")  # fmt: skip
        print(line, flush=True)


def part_bc(page: Any, args: argparse.Namespace, pose: list[Any] | None) -> None:
    idle = cpu_share(4, page)
    size = page.evaluate(CAMERA_JS)
    page.wait_for_timeout(2000)
    rate = page.evaluate(CAMERA_RATE_JS, 3)
    playing = cpu_share(6, page)
    print(f"\n(c) the camera: {size[0]} x {size[1]} at {rate:.1f} frames/s; Chromium's CPU while a page only plays it "
          f"{playing:.2f} core (idle page {idle:.2f}), load {os.getloadavg()[0]:.1f}")  # fmt: skip
    print(f"\n(b) the page's work per frame, {args.grabs} camera frames each")
    for way, width in [("bitmap", None), *[("bitmap-resized", v) for v in args.widths], ("videoframe", None)]:
        try:
            ms = page.evaluate(GRAB_JS, {"n": args.grabs, "way": way, "width": width})
        except Exception as err:  # noqa: BLE001 - a way this Chromium lacks is reported, not fatal
            print(f"  {way}: failed ({str(err).splitlines()[0]})")
            continue
        what = f"{way} {width}" if width else way
        print(f"  grab, {what}: p50 {statistics.median(ms):.2f} ms, p95 {percentile(ms, 95):.2f} ms")
    if pose is not None:
        ms = page.evaluate(DRAW_JS, {"n": args.grabs, "pose": pose})
        print(f"  the overlay's drawing: p50 {statistics.median(ms):.2f} ms, p95 {percentile(ms, 95):.2f} ms")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--model", default="lite", choices=["lite", "full"])
    parser.add_argument("--blocks", type=int, default=4, help="blocks per variant, alternating")
    parser.add_argument("--block", type=int, default=30, help="frames per block")
    parser.add_argument("--widths", type=int, nargs="*", default=[480, 320], help="downscaled widths (px)")
    parser.add_argument("--grabs", type=int, default=60, help="camera frames per way of grabbing")
    parser.add_argument("--skip-a", action="store_true", help="only (b) and (c)")
    parser.add_argument("--port", type=int, default=8104)
    args = parser.parse_args(argv)
    from playwright.sync_api import sync_playwright

    from bench.camera_page import prepare
    from tests.fake_camera import sports2d_y4m

    with tempfile.TemporaryDirectory() as tmp:
        frames = clip_frames("sports2d", Path(tmp))
        clip = sports2d_y4m(Path(tmp) / "camera.y4m")
        h, w = frames[0].shape[:2]
        db_url = f"sqlite:///{tmp}/bench.db"
        prepare(db_url)
        server = start_server(db_url, args.port, 1)
        try:
            with sync_playwright() as pw:
                browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=[
                    "--no-sandbox", "--use-fake-device-for-media-stream", "--use-fake-ui-for-media-stream",
                    f"--use-file-for-fake-video-capture={clip}"])  # fmt: skip
                page = browser.new_page(base_url=f"http://127.0.0.1:{args.port}")
                page.set_default_timeout(600_000)
                page.goto("/")
                print(f"Chromium {browser.version}, WebGL: {page.evaluate(RENDERER_JS)}, {os.cpu_count()} cores")
                pose = None
                if not args.skip_a:
                    for f in frames:
                        rgba = base64.b64encode(np.dstack([f, np.full((h, w), 255, np.uint8)]).tobytes()).decode()
                        page.evaluate(ADD_FRAME_JS, {"rgba": rgba, "width": w, "height": h})
                    part_a(page, args, len(frames), w, h)
                    page.close()
                    page = browser.new_page(base_url=f"http://127.0.0.1:{args.port}")
                    page.goto("/")
                part_bc(page, args, pose or [[0.5, 0.2 + i * 0.02, 0.9] for i in range(33)])
                browser.close()
        finally:
            stop_server(server)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
