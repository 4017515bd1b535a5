/* The pose landmarker for the page: it runs in a worker (camera_pose_worker.js: MediaPipe Tasks Vision's WebAssembly
 * and the pinned BlazePose model, both served by the app from /static/vendor/mediapipe/; nothing fetched from another
 * site; the page's and the worker's CSP allow 'wasm-unsafe-eval' and connections to this origin only), so a
 * detection does not hold the page's main thread. GPU delegate when the browser gives one, else CPU.
 * The skeleton overlay is drawn here too. */
"use strict";
const CameraPose = (() => {
  const BASE = () => Coach.url("/static/vendor/mediapipe");
  const BONES = [[11, 12], [11, 13], [13, 15], [12, 14], [14, 16], [11, 23], [12, 24], [23, 24], [23, 25], [25, 27],
    [27, 31], [24, 26], [26, 28], [28, 32], [0, 11], [0, 12]];
  let worker = null, loading = null, nextId = 0;
  const waiting = new Map();  // detection id -> its promise's resolve
  const info = { model: null, delegate: null };

  function started() {
    if (worker) return worker;
    worker = new Worker(Coach.url("/static/camera_pose_worker.js"), { type: "module" });
    worker.onmessage = ({ data }) => {
      if (data.type === "result") { waiting.get(data.id)(data.result); waiting.delete(data.id); return; }
      const done = loading; loading = null;
      if (done) done(data);
    };
    worker.onerror = (err) => {  // the worker could not start: every caller gets an answer
      console.error(err);
      for (const resolve of waiting.values()) resolve(null);
      waiting.clear();
      if (loading) { loading({ type: "failed", error: err.message || "worker failed" }); loading = null; }
    };
    return worker;
  }

  /** Loads the landmarker with model "lite" or "full"; delegate "GPU" first unless only: "CPU". Throws on failure. */
  async function load(model, only) {
    const w = started();
    const out = await new Promise((resolve) => {
      loading = resolve;
      w.postMessage({ type: "load", base: new URL(BASE(), location.href).href, model, delegates: only ? [only] : ["GPU", "CPU"] });
    });
    if (out.type !== "loaded") throw new Error(out.error);
    info.model = out.model; info.delegate = out.delegate;
    return info;
  }

  /** Resolves to the landmarker's result for the video's current frame ({landmarks, worldLandmarks}), or null.
   *  nowMs: the frame's timestamp (ms, increasing). */
  async function detect(video, nowMs) {
    const frame = await createImageBitmap(video);
    const id = nextId++;
    return new Promise((resolve) => {
      waiting.set(id, resolve);
      started().postMessage({ type: "detect", id, frame, ms: nowMs }, [frame]);
    });
  }

  /** Draws the followed pose (image landmarks) over the picture; other poses thin and grey. */
  function draw(canvas, video, result, followed) {
    const w = video.videoWidth || 640, h = video.videoHeight || 480;
    if (canvas.width !== w) canvas.width = w;
    if (canvas.height !== h) canvas.height = h;
    const g = canvas.getContext("2d");
    g.clearRect(0, 0, w, h);
    (result && result.landmarks ? result.landmarks : []).forEach((pose, i) => {
      const mine = i === followed;
      g.strokeStyle = mine ? "#ffbf00" : "#9a9a9a";
      g.fillStyle = mine ? "#0b4f9c" : "#9a9a9a";
      g.lineWidth = Math.max(2, w / (mine ? 120 : 320));
      for (const [a, b] of BONES) {
        g.beginPath(); g.moveTo(pose[a].x * w, pose[a].y * h); g.lineTo(pose[b].x * w, pose[b].y * h); g.stroke();
      }
      if (mine) for (const l of pose) { g.beginPath(); g.arc(l.x * w, l.y * h, w / 160, 0, 2 * Math.PI); g.fill(); }
    });
  }

  return { load, detect, draw, info };
})();
