/* The pose landmarker itself, an ES module: MediaPipe Tasks Vision's module build and the pinned model, both from
 * /static/vendor/mediapipe/ on this origin. It runs in the landmarker's worker (camera_pose_worker.js imports it),
 * or on the page itself when the browser cannot start that worker (camera_pose.js imports it): one code for both.
 * load({base, model: "lite"|"full", delegates: ["GPU", "CPU"] | ["CPU"], mode?}) -> {type: "loaded", model, delegate}
 *                                                                            | {type: "failed", error}
 *   mode: "VIDEO" (the page's: tracks the person from frame to frame and smooths) unless "IMAGE" (each frame on its
 *   own, ms unused: tests/frontend/test_camera_runtimes.py holds it equal to the agent's Python runtime).
 * detect({id, frame: ImageBitmap (closed here), ms: timestamp in ms, increasing})
 *   -> {type: "result", id, result: {landmarks, worldLandmarks} | null (no landmarker yet, or it failed)} */
let vision = null, fileset = null, landmarker = null, image = false;

export async function load({ base, model, delegates, mode }) {
  try {
    if (!vision) vision = await import(base + "/vision_bundle.mjs");
    // the WebAssembly's loader: in a (module) worker its module build, which the bundle import()s; on the page its
    // classic build, which the bundle adds as a <script> (a classic script cannot run the module build)
    if (!fileset) fileset = await vision.FilesetResolver.forVisionTasks(base + "/wasm", typeof document === "undefined");
  } catch (err) { return { type: "failed", error: String(err) }; }
  if (landmarker) { landmarker.close(); landmarker = null; }
  let last = null;
  for (const delegate of delegates) {
    try {
      landmarker = await vision.PoseLandmarker.createFromOptions(fileset, {
        baseOptions: { modelAssetPath: `${base}/pose_landmarker_${model}.task`, delegate },
        runningMode: mode === "IMAGE" ? "IMAGE" : "VIDEO", numPoses: 2,
        minPoseDetectionConfidence: 0.5, minPosePresenceConfidence: 0.5, minTrackingConfidence: 0.5,
        outputSegmentationMasks: false,
      });
      image = mode === "IMAGE";
      return { type: "loaded", model, delegate };
    } catch (err) { last = err; }
  }
  return { type: "failed", error: String(last || "no delegate") };  // i18n: not shown (the console)
}

export function detect({ id, frame, ms }) {
  let result = null;
  try {
    if (landmarker) {
      const r = image ? landmarker.detect(frame) : landmarker.detectForVideo(frame, ms);
      result = { landmarks: r.landmarks, worldLandmarks: r.worldLandmarks };
    }
  } catch (err) { console.error(err); }
  frame.close();
  return { type: "result", id, result };
}
