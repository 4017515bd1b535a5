/* The pose landmarker itself, an ES module: MediaPipe Tasks Vision's module build and the pinned model, both from
 * /static/vendor/mediapipe/ on this origin. It runs in the landmarker's worker (camera_pose_worker.js imports it),
 * or on the page itself when the browser cannot start that worker (camera_pose.js imports it): one code for both.
 *
 * The page's landmarker is a "company watch", the same as the home agent's (kinect_agent/sources/webcam/company.py,
 * whose docstring has the reasons and the measurements): MediaPipe runs its person detector on every frame while it
 * tracks fewer people than it looks for, so looking for two people when the patient is alone halves the frame rate.
 * `one` (numPoses 1: it tracks the patient from frame to frame) runs on every frame while the patient is alone;
 * `two` (numPoses 2) looks on the same frame once every CHECK_MS, and on every frame (`one` on none) from when it
 * finds two people until it has found at most one for ALONE_MS: with two people in view the page gets both poses
 * from a landmarker looking for two on every frame, as before the watch (camera_checks.js keeps the patient and says
 * so). A second person the detector scores low is noticed some seconds later than before (one look a second).
 *
 * load({base, model: "lite"|"full", delegates: ["GPU", "CPU"] | ["CPU"], mode?, poses?})
 *     -> {type: "loaded", model, delegate} | {type: "failed", error}
 *   mode "IMAGE" (each frame on its own, ms unused) or poses (1 or 2): one plain landmarker looking for that many
 *   people (2 by default) in that mode (VIDEO by default), not the watch: tests/frontend/test_camera_runtimes.py holds
 *   it equal to the agent's Python runtime.
 * detect({id, frame: ImageBitmap (closed here), ms: timestamp in ms, increasing})
 *   -> {type: "result", id, result: {landmarks, worldLandmarks, by: "one"|"two"|"plain", company: bool, took} | null
 *       (no landmarker yet, or it failed)}; by: the landmarker whose poses these are; company: `two` runs on the next
 *       frame; took: {detect_ms: the whole detection here, look_ms: `two`'s look on a frame `one` answered, or 0} (ms, for
 *       bench/camera_page.py and bench/camera_frame_costs.py). */
export const CHECK_MS = 1000;  // alone: `two` looks for a second person at most this long apart (ms)
export const ALONE_MS = 1000;  // in company: back to `one` after this long without a second person (ms)
export const TWO_DETECTION = 0.5;  // `two`'s person detection threshold, as `one`'s (MediaPipe's default)

let vision = null, fileset = null, plain = null, image = false;
let watch = null;  // {one, two (null while it loads), company, checkedMs, twoSeenMs}
let lookMs = 0;  // the time `two` took on the frame being detected (ms; 0 when it did not look)

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
  if (typeof document === "undefined" && !self.ModuleFactory) {
    self.ModuleFactory = (await import(fileset.wasmLoaderPath)).default;
  }
  return vision.PoseLandmarker.createFromOptions(fileset, {
    baseOptions: { modelAssetPath: `${base}/pose_landmarker_${model}.task`, delegate },
    runningMode, numPoses,
    minPoseDetectionConfidence: detection, minPosePresenceConfidence: 0.5, minTrackingConfidence: 0.5,
    outputSegmentationMasks: false,
  });
}

export async function load({ base, model, delegates, mode, poses }) {
  try {
    if (!vision) vision = await import(base + "/vision_bundle.mjs");
    // the WebAssembly's loader: in a (module) worker its module build, which the bundle import()s; on the page its
    // classic build, which the bundle adds as a <script> (a classic script cannot run the module build)
    if (!fileset) fileset = await vision.FilesetResolver.forVisionTasks(base + "/wasm", typeof document === "undefined");
  } catch (err) { return { type: "failed", error: String(err) }; }
  closeAll();
  let last = null;
  for (const delegate of delegates) {
    try {
      if (mode === "IMAGE" || poses) {
        image = mode === "IMAGE";
        plain = await create(model, delegate, base, poses || 2, image ? "IMAGE" : "VIDEO");
      } else {
        const one = await create(model, delegate, base, 1, "VIDEO");
        image = false;
        // `two` loads after `one` answers: the first frames (and, after a worker died mid-set, the page's) do not wait
        // for a second WebAssembly instance; until it is there, `one` answers alone
        const mine = { one, two: null, company: false, checkedMs: null, twoSeenMs: 0 };
        watch = mine;
        create(model, delegate, base, 2, "VIDEO", TWO_DETECTION)
          .then((two) => { if (watch === mine) mine.two = two; else two.close(); })
          .catch((err) => console.error(err));  // i18n: not shown (the console); `one` goes on alone
      }
      return { type: "loaded", model, delegate };
    } catch (err) { last = err; }
  }
  return { type: "failed", error: String(last || "no delegate") };  // i18n: not shown (the console)
}

/** `two` on the frame: notes when it looked and whether it found two people (then the watch is in company). */
function looked(frame, ms) {
  const began = performance.now();
  const r = watch.two.detectForVideo(frame, ms);
  lookMs = performance.now() - began;
  watch.checkedMs = ms;
  if (r.landmarks.length >= 2) { watch.company = true; watch.twoSeenMs = ms; }
  return r;
}

/** Returns [MediaPipe's result, "one" | "two"] for the frame: see the module's comment. */
function watched(frame, ms) {
  if (!watch.two) return [watch.one.detectForVideo(frame, ms), "one"];
  if (watch.company) {
    const r = looked(frame, ms);
    if (r.landmarks.length < 2 && ms - watch.twoSeenMs >= ALONE_MS) watch.company = false;
    return [r, "two"];
  }
  const r = watch.one.detectForVideo(frame, ms);
  if (watch.checkedMs === null || ms - watch.checkedMs >= CHECK_MS) {
    const both = looked(frame, ms);
    if (watch.company) return [both, "two"];  // someone else is in view: both people, as `two` sees them
  }
  return [r, "one"];
}

export function detect({ id, frame, ms }) {
  let result = null;
  const began = performance.now();
  lookMs = 0;
  try {
    if (watch) {
      const [r, by] = watched(frame, ms);
      result = { landmarks: r.landmarks, worldLandmarks: r.worldLandmarks, by, company: watch.company };
    } else if (plain) {
      const r = image ? plain.detect(frame) : plain.detectForVideo(frame, ms);
      result = { landmarks: r.landmarks, worldLandmarks: r.worldLandmarks, by: "plain", company: false };
    }
  } catch (err) { console.error(err); }
  frame.close();
  if (result) result.took = { detect_ms: performance.now() - began, look_ms: lookMs };
  return { type: "result", id, result };
}
