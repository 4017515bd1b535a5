/* The pose landmarker itself, an ES module: MediaPipe Tasks Vision's module build and the pinned model, both from
 * /static/vendor/mediapipe/ on this origin. It runs in the landmarker's worker (camera_pose_worker.js imports it),
 * or on the page itself when the browser cannot start that worker (camera_pose.js imports it): one code for both.
 *
 * The page's landmarker is a "company watch", the same as the home agent's (kinect_agent/sources/webcam/company.py,
 * whose docstring has the reasons and the measurements): MediaPipe runs its person detector on every frame while it
 * tracks fewer people than it looks for, so looking for two people when the patient is alone halves the frame rate.
 * `one` (numPoses 1: it tracks the patient from frame to frame) runs on every frame while the patient is alone;
 * `two` (numPoses 2) looks on a copy of the same frame once every CHECK_MS, and on every frame (`one` on none) from
 * when it finds two people until it has found at most one for ALONE_MS: with two people in view the page gets both
 * poses from a landmarker looking for two on every frame, as before the watch (camera_checks.js keeps the patient and
 * says so). A second person the detector scores low is noticed some seconds later than before (one look a second).
 * In a worker, `two` runs in a worker of its own, started from this one: its look (2-3 times a tracking frame's
 * time) runs beside `one`'s tracking instead of holding a frame (bench/README.md, "Where a camera frame's time
 * goes"). On the page (no worker) it looks in line, before `one`. Either way what a look found takes effect from the
 * first frame after its answer (the agent's watch: already on the frame it looked at).
 *
 * load({base, model: "lite"|"full", delegates: ["GPU", "CPU"] | ["CPU"], mode?, poses?, detection?})
 *     -> {type: "loaded", model, delegate} | {type: "failed", error}
 *   mode "IMAGE" (each frame on its own, ms unused) or poses (1 or 2): one plain landmarker looking for that many
 *   people (2 by default) in that mode (VIDEO by default), with that person detection threshold (0.5 by default), not
 *   the watch: tests/frontend/test_camera_runtimes.py holds it equal to the agent's Python runtime.
 * detect({id, frame: ImageBitmap (closed here), ms: timestamp in ms, increasing}), async, one call at a time
 *   -> {type: "result", id, result: {landmarks, worldLandmarks, by: "one"|"two"|"plain", company: bool, took} | null
 *       (no landmarker yet, or it failed)}; by: the landmarker whose poses these are; company: `two` runs on the next
 *       frame; took: {detect_ms: the whole detection here, look_ms: the last look's time in `two`, on the first
 *       frame after it answered, else 0} (ms, for bench/camera_page.py and bench/camera_frame_costs.py). */
export const CHECK_MS = 1000;  // alone: `two` looks for a second person at most this long apart (ms)
export const ALONE_MS = 1000;  // in company: back to `one` after this long without a second person (ms)
export const TWO_DETECTION = 0.5;  // `two`'s person detection threshold, as `one`'s (MediaPipe's default)

let vision = null, fileset = null, plain = null, image = false;
// {one, two: {detect, close} (null while it loads, or after it failed), company, checkedMs, twoSeenMs, looking,
//  lookMs: the last look's time, until reported}
let watch = null;

function closeAll() {
  for (const l of [plain, watch && watch.one, watch && watch.two]) if (l) l.close();
  plain = null; watch = null;
}

async function create(model, delegate, base, numPoses, runningMode, detection = 0.5) {
  // In a module worker MediaPipe import()s the WebAssembly's loader, which sets self.ModuleFactory when it is first
  // evaluated, and clears it once used: a second landmarker in the same worker (the watch's `two`; the lighter model
  // after a slow start) would fail with "ModuleFactory not set." (and, before the watch, moved the landmarker onto
  // the page). The loader's module is evaluated once; its export is the same factory, set again here. On the page
  // MediaPipe adds the classic loader as a new <script> each time, which sets it itself.
  if (inWorker() && !self.ModuleFactory) {
    self.ModuleFactory = (await import(fileset.wasmLoaderPath)).default;
  }
  return vision.PoseLandmarker.createFromOptions(fileset, {
    baseOptions: { modelAssetPath: `${base}/pose_landmarker_${model}.task`, delegate },
    runningMode, numPoses,
    minPoseDetectionConfidence: detection, minPosePresenceConfidence: 0.5, minTrackingConfidence: 0.5,
    outputSegmentationMasks: false,
  });
}

function inWorker() { return typeof document === "undefined"; }

/** Returns `two` looking in line, on this thread: {detect(frame (closed), ms) -> Promise<{landmarks, worldLandmarks,
 *  took}>, close()}. */
async function twoHere(model, delegate, base) {
  const l = await create(model, delegate, base, 2, "VIDEO", TWO_DETECTION);
  return {
    detect: async (frame, ms) => {
      const began = performance.now();
      try {
        const r = l.detectForVideo(frame, ms);
        return { landmarks: r.landmarks, worldLandmarks: r.worldLandmarks, took: { detect_ms: performance.now() - began } };
      } finally { frame.close(); }
    },
    close: () => l.close(),
  };
}

/** Returns `two` in a worker of its own (this module again, as a plain landmarker looking for two people), with the
 *  same detect and close as twoHere; its detect answers null once that worker failed. Null when it cannot load. */
function twoApart(model, delegate, base) {
  const worker = new Worker(new URL("./camera_pose_worker.js", import.meta.url), { type: "module" });
  const waiting = new Map();
  let next = 0, dead = false;
  const two = {
    detect: (frame, ms) => new Promise((resolve) => {
      if (dead) { frame.close(); resolve(null); return; }
      const id = next++;
      waiting.set(id, resolve);
      worker.postMessage({ type: "detect", id, frame, ms }, [frame]);
    }),
    close: () => {  // a detection waiting for it answers null (a new load closes the watch between two frames)
      dead = true; worker.terminate();
      for (const done of waiting.values()) done(null);
      waiting.clear();
    },
  };
  return new Promise((resolve) => {
    worker.onmessage = ({ data }) => {
      if (data.type === "result") { const done = waiting.get(data.id); waiting.delete(data.id); if (done) done(data.result); }
      else if (data.type === "loaded") resolve(two);
      else { two.close(); resolve(null); }
    };
    worker.onerror = (event) => {  // it could not start, or died: `one` goes on alone
      event.preventDefault();
      dead = true;
      for (const done of waiting.values()) done(null);
      waiting.clear();
      resolve(null);
    };
    worker.postMessage({ type: "load", base, model, delegates: [delegate], poses: 2, detection: TWO_DETECTION });
  });
}

export async function load({ base, model, delegates, mode, poses, detection }) {
  try {
    if (!vision) vision = await import(base + "/vision_bundle.mjs");
    // the WebAssembly's loader: in a (module) worker its module build, which the bundle import()s; on the page its
    // classic build, which the bundle adds as a <script> (a classic script cannot run the module build)
    if (!fileset) fileset = await vision.FilesetResolver.forVisionTasks(base + "/wasm", inWorker());
  } catch (err) { return { type: "failed", error: String(err) }; }
  closeAll();
  let last = null;
  for (const delegate of delegates) {
    try {
      if (mode === "IMAGE" || poses) {
        image = mode === "IMAGE";
        plain = await create(model, delegate, base, poses || 2, image ? "IMAGE" : "VIDEO", detection ?? 0.5);
      } else {
        const one = await create(model, delegate, base, 1, "VIDEO");
        image = false;
        // `two` loads after `one` answers: the first frames (and, after a worker died mid-set, the page's) do not wait
        // for a second WebAssembly instance; until it is there, `one` answers alone
        const mine = { one, two: null, company: false, checkedMs: null, twoSeenMs: 0, looking: false, lookMs: 0 };
        watch = mine;
        const apart = inWorker() && typeof Worker !== "undefined";
        (apart ? twoApart(model, delegate, base) : twoHere(model, delegate, base))
          .then((two) => { if (watch === mine) mine.two = two; else if (two) two.close(); })
          .catch((err) => console.error(err));  // i18n: not shown (the console); `one` goes on alone
      }
      return { type: "loaded", model, delegate };
    } catch (err) { last = err; }
  }
  return { type: "failed", error: String(last || "no delegate") };  // i18n: not shown (the console)
}

/** Starts `two`'s look at `copy` (a copy of the frame at ms, closed by `two`): when it answers with two people,
 *  the watch is in company from the next frame on. */
function look(copy, ms) {
  const mine = watch;
  if (!mine || !mine.two) { copy.close(); return; }  // closed meanwhile (a new load)
  mine.looking = true; mine.checkedMs = ms;
  mine.two.detect(copy, ms).then((r) => {
    mine.looking = false;
    if (!r) { if (mine.two) mine.two.close(); mine.two = null; return; }  // `two` failed: `one` goes on alone
    mine.lookMs = r.took.detect_ms;
    if (r.landmarks.length >= 2) { mine.company = true; mine.twoSeenMs = ms; }
  });
}

/** Resolves to [MediaPipe's result, "one" | "two"] for the frame, or null (`two` failed on it): see the module's
 *  comment. */
async function watched(frame, ms) {
  const mine = watch;
  if (mine.two && mine.company) {
    const r = await mine.two.detect(frame, ms);
    if (!r) { mine.two.close(); mine.two = null; mine.company = false; return null; }
    if (r.landmarks.length >= 2) mine.twoSeenMs = ms;
    else if (ms - mine.twoSeenMs >= ALONE_MS) mine.company = false;  // `one` from the next frame on
    return [r, "two"];
  }
  if (mine.two && !mine.looking && (mine.checkedMs === null || ms - mine.checkedMs >= CHECK_MS)) {
    look(await createImageBitmap(frame), ms);  // in a worker `two` looks while `one` tracks
  }
  return [mine.one.detectForVideo(frame, ms), "one"];
}

export async function detect({ id, frame, ms }) {
  let result = null;
  const began = performance.now();
  try {
    if (watch) {
      const mine = watch;
      const out = await watched(frame, ms);
      if (out) {
        const [r, by] = out;
        result = { landmarks: r.landmarks, worldLandmarks: r.worldLandmarks, by, company: mine.company,
          took: { detect_ms: performance.now() - began, look_ms: mine.lookMs } };
        mine.lookMs = 0;
      }
    } else if (plain) {
      const r = image ? plain.detect(frame) : plain.detectForVideo(frame, ms);
      result = { landmarks: r.landmarks, worldLandmarks: r.worldLandmarks, by: "plain", company: false,
        took: { detect_ms: performance.now() - began, look_ms: 0 } };
    }
  } catch (err) { console.error(err); }
  frame.close();
  return { type: "result", id, result };
}
