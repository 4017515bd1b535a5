"""The camera page's pose landmarker alone, A/B in one headless Chromium: the page's worker
(frontend/static/camera_pose_worker.js) loaded twice on the same page, once as the page runs it (the company watch:
one person tracked, a look for a second once a second) and once as a plain landmarker looking for two people on every
frame (the page before the watch), fed the same frames in alternating blocks, so that both see the same machine load.

Frames: the camera tests' clip (Sports2D's demo, BSD-3-Clause, tests/fake_camera.py: 640 x 360, a woman walking
past and a man on a hut, two people in view much of the time) every second frame (15 a second, about the page's
pace), decoded once into ImageBitmaps on the page; each detection gets a copy (the worker closes what it gets) and
is timed from the copy's postMessage to the answer. `--clip alone` crops the clip to the walker's strip below the
hut (one person in view, then nobody), the case of a patient alone at home.

    python bench/camera_landmarker.py [--model lite] [--blocks 6] [--block 30] [--clip sports2d|alone]

Prints, per scheme, detections per second (the frames of all its blocks over their summed times), p50 and p95 ms per
frame, the share of frames the watch's single tracker answered, and the people found per frame.
"""

from __future__ import annotations

import argparse
import base64
import os
import statistics
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench.dashboard_load import percentile, start_server, stop_server  # noqa: E402

CHROMIUM = "/usr/bin/chromium"
FRAME_MS = 66  # the time stamps of frames 15 a second

ADD_FRAME_JS = """async ({ rgba, width, height }) => {
  window.__frames = window.__frames || [];
  const bytes = Uint8ClampedArray.from(atob(rgba), (c) => c.charCodeAt(0));
  window.__frames.push(await createImageBitmap(new ImageData(bytes, width, height)));
  return window.__frames.length;
}"""

LOAD_JS = """async ({ name, model, mode, poses }) => {
  const worker = new Worker("/static/camera_pose_worker.js", { type: "module" });
  window.__workers = window.__workers || {};
  window.__workers[name] = { worker, next: 0, ms: 0 };
  const base = new URL("/static/vendor/mediapipe", location.href).href;
  const message = { type: "load", base, model, delegates: ["CPU"] };
  if (poses) message.poses = poses;
  if (mode) message.mode = mode;
  return await new Promise((resolve) => {
    worker.onmessage = ({ data }) => resolve(data);
    worker.postMessage(message);
  });
}"""

BLOCK_JS = """async ({ name, start, n, frameMs }) => {
  const w = window.__workers[name];
  const out = [];
  for (let k = 0; k < n; k++) {
    const src = window.__frames[(start + k) % window.__frames.length];
    const frame = await createImageBitmap(src);
    const id = w.next++;
    w.ms += frameMs;
    const began = performance.now();
    const result = await new Promise((resolve) => {
      w.worker.onmessage = ({ data }) => { if (data.type === "result" && data.id === id) resolve(data.result); };
      w.worker.postMessage({ type: "detect", id, frame, ms: w.ms }, [frame]);
    });
    out.push([performance.now() - began, result ? result.landmarks.length : -1, result ? result.by : null]);
  }
  return out;
}"""


def clip_frames(clip: str, folder: Path) -> list[np.ndarray]:
    """Returns the RGB frames (360, 640, 3) fed to the landmarker: every second frame of the camera tests' clip, or
    of its walker's strip (clip "alone")."""
    from tests.fake_camera import read_y4m, sports2d_y4m, y4m_frame_count

    kwargs: dict[str, Any] = {"crop": ALONE_CROP} if clip == "alone" else {}
    path = sports2d_y4m(folder / f"{clip}.y4m", **kwargs)
    return read_y4m(path, list(range(0, y4m_frame_count(path), 2)))


ALONE_CROP = (0.0, 0.47, 1.0, 1.0)  # x0, y0, x1, y1 of the demo's picture: below the hut's roof, the walker only


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--model", default="lite", choices=["lite", "full"])
    parser.add_argument("--blocks", type=int, default=6, help="blocks per scheme, alternating")
    parser.add_argument("--block", type=int, default=30, help="frames per block")
    parser.add_argument("--clip", default="sports2d", choices=["sports2d", "alone"])
    parser.add_argument("--port", type=int, default=8103)
    args = parser.parse_args(argv)
    from playwright.sync_api import sync_playwright

    from bench.camera_page import prepare

    with tempfile.TemporaryDirectory() as tmp:
        frames = clip_frames(args.clip, Path(tmp))
        h, w = frames[0].shape[:2]
        db_url = f"sqlite:///{tmp}/bench.db"
        prepare(db_url)
        server = start_server(db_url, args.port, 1)
        try:
            with sync_playwright() as pw:
                browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=["--no-sandbox"])
                page = browser.new_page(base_url=f"http://127.0.0.1:{args.port}")
                page.goto("/")
                for f in frames:  # one at a time: the whole clip in one call is too large for the page
                    rgba = base64.b64encode(np.dstack([f, np.full((h, w), 255, np.uint8)]).tobytes()).decode()
                    page.evaluate(ADD_FRAME_JS, {"rgba": rgba, "width": w, "height": h})
                for name, poses in (("watch", None), ("two", 2)):
                    loaded = page.evaluate(LOAD_JS, {"name": name, "model": args.model, "poses": poses})
                    assert loaded["type"] == "loaded", loaded
                    page.evaluate(BLOCK_JS, {"name": name, "start": 0, "n": 10, "frameMs": FRAME_MS})  # warm-up
                rows: dict[str, list[list[Any]]] = {"watch": [], "two": []}
                for b in range(args.blocks):
                    for name in ("watch", "two") if b % 2 == 0 else ("two", "watch"):
                        start = b * args.block  # both schemes see the same frames in the same order
                        rows[name] += page.evaluate(BLOCK_JS, {"name": name, "start": start, "n": args.block,
                                                               "frameMs": FRAME_MS})  # fmt: skip
                browser.close()
        finally:
            stop_server(server)
    print(f"\n{args.model}, clip {args.clip} ({len(frames)} frames of {w} x {h}), {args.blocks} blocks of "
          f"{args.block} frames per scheme, load average {os.getloadavg()[0]:.1f} at the end")  # fmt: skip
    for name, what in (("watch", "the watch (the page now)"), ("two", "two people on every frame (before)")):
        ms = [r[0] for r in rows[name]]
        people = [r[1] for r in rows[name]]
        single = sum(r[2] == "one" for r in rows[name]) / len(rows[name])
        print(f"  {what}: {1000 * len(ms) / sum(ms):.1f} frames/s, p50 {statistics.median(ms):.0f} ms, "
              f"p95 {percentile(ms, 95):.0f} ms; single tracker {single:.0%} of frames; people per frame "
              f"{ {k: people.count(k) for k in sorted(set(people))} }")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
