/* The pose landmarker for the page: camera_pose_core.js (MediaPipe Tasks Vision's WebAssembly and the pinned
 * BlazePose model, both served by the app from /static/vendor/mediapipe/; nothing fetched from another site; the
 * page's and the worker's CSP allow 'wasm-unsafe-eval' and connections to this origin only). It runs in a worker
 * (camera_pose_worker.js), so a detection does not hold the page's main thread; in a browser that cannot start or
 * keep that worker (no module workers: Firefox before 114, Safari before 15) it runs on the page itself, slower but
 * counting. GPU delegate when the browser gives one, else CPU. The skeleton overlay is drawn here too. */
"use strict";
const CameraPose = (() => {
  const BASE = () => Coach.url("/static/vendor/mediapipe");
  const BONES = [[11, 12], [11, 13], [13, 15], [12, 14], [14, 16], [11, 23], [12, 24], [23, 24], [23, 25], [25, 27],
    [27, 31], [24, 26], [26, 28], [28, 32], [0, 11], [0, 12]];
  const SILENT_MS = 8000;  // a detection takes 60-150 ms, a few s on a crowded slow computer: longer, the worker died
  let worker = null, loading = null, nextId = 0;
  let onPage = null;  // camera_pose_core.js imported into the page, once the worker failed
  let lastLoad = null;  // the last load message, to load again on the page when the worker dies mid-set
  const waiting = new Map();  // detection id -> its promise's resolve
  // where the landmarker runs: "worker" | "page"; "lost" (the worker died), "loading" (onto the page), "failed"
  const info = { model: null, delegate: null, where: null };

  /** The worker, started on first use; throws when the browser cannot start a module worker. */
  function started() {
    if (worker) return worker;
    worker = new Worker(Coach.url("/static/camera_pose_worker.js"), { type: "module" });
    worker.onmessage = ({ data }) => {
      if (data.type === "result") {
        const done = waiting.get(data.id);
        waiting.delete(data.id);
        if (done) done(data.result);
        return;
      }
      const done = loading; loading = null;
      if (done) done(data);
    };
    worker.onerror = (event) => {  // the worker could not start, or died
      event.preventDefault();
      lose(event.message || "the landmarker's worker failed");  // i18n: not shown (the console)
    };
    return worker;
  }

  /** Ends the worker: every caller waiting for it gets an answer; a landmarker loaded there is "lost" (the next
   *  detection loads it on the page). */
  function lose(error) {
    console.warn(error);
    if (worker) { worker.terminate(); worker = null; }
    if (info.where === "worker") info.where = "lost";
    for (const resolve of waiting.values()) resolve(null);
    waiting.clear();
    if (loading) { loading({ type: "failed", error }); loading = null; }
  }

  function inWorker(message) {
    return new Promise((resolve) => {
      try { loading = resolve; started().postMessage(message); }
      catch (err) { loading = null; resolve({ type: "failed", error: String(err) }); }
    });
  }

  async function onThePage(message) {
    try { if (!onPage) onPage = await import(Coach.url("/static/camera_pose_core.js")); }
    catch (err) { return { type: "failed", error: String(err) }; }
    return onPage.load(message);
  }

  /** Loads the landmarker with model "lite" or "full"; delegate "GPU" first unless only: "CPU"; in the worker, or on
   *  the page when the worker fails. Throws when neither can load it. */
  async function load(model, only) {
    const message = { type: "load", base: new URL(BASE(), location.href).href, model, delegates: only ? [only] : ["GPU", "CPU"] };
    lastLoad = message;
    let out = onPage ? await onPage.load(message) : await inWorker(message), where = onPage ? "page" : "worker";
    if (out.type !== "loaded" && !onPage) {
      console.warn(`the pose landmarker runs on the page: its worker failed (${out.error})`);  // i18n: not shown
      out = await onThePage(message); where = "page";
    }
    if (out.type !== "loaded") throw new Error(out.error);
    info.model = out.model; info.delegate = out.delegate; info.where = where;
    return info;
  }

  /** Resolves to the landmarker's result for the video's current frame ({landmarks, worldLandmarks}), or null.
   *  nowMs: the frame's timestamp (ms, increasing). */
  async function detect(video, nowMs) {
    if (info.where === "lost") {  // the worker died after loading: the page loads the landmarker and goes on
      info.where = "loading";
      const out = await onThePage(lastLoad);
      info.where = out.type === "loaded" ? "page" : "failed";
    }
    if (info.where === "failed") throw new Error("the pose landmarker could not run on this page either");  // i18n: not shown (the page says T.trackerFailed)
    if (info.where === "loading") return null;
    const grabbed = performance.now();
    const frame = await createImageBitmap(video);
    const sent = performance.now();
    const id = nextId++;
    const timed = (result) => {  // for benchmarks: the grab and the round trip (ms), with the worker's own part
      if (result) result.took = { ...result.took, grab_ms: sent - grabbed, trip_ms: performance.now() - sent };
      return result;
    };
    if (onPage && info.where === "page") return timed((await onPage.detect({ id, frame, ms: nowMs })).result);
    const timer = setTimeout(() => lose(`the landmarker's worker gave no answer in ${SILENT_MS} ms`), SILENT_MS);  // i18n: not shown
    return new Promise((resolve) => {
      waiting.set(id, (result) => { clearTimeout(timer); resolve(timed(result)); });
      try { started().postMessage({ type: "detect", id, frame, ms: nowMs }, [frame]); }
      catch (err) { lose(String(err)); }
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
