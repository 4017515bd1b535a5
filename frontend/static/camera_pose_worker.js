/* The pose landmarker in a worker (module worker, started by camera_pose.js), so that a detection (60-150 ms a
 * frame on a slow CPU) does not hold the page's main thread: the batch answers and the count are drawn meanwhile.
 * MediaPipe Tasks Vision's module build and the pinned model, both from /static/vendor/mediapipe/ on this origin.
 * Messages in:  {type: "load", base, model: "lite"|"full", delegates: ["GPU", "CPU"] | ["CPU"], mode?}
 *               {type: "detect", id, frame: ImageBitmap (transferred, closed here), ms: timestamp in ms, increasing}
 * mode: "VIDEO" (the page's: tracks the person from frame to frame and smooths) unless "IMAGE" (each frame on its
 * own, ms unused: tests/frontend/test_camera_runtimes.py holds it equal to the agent's Python runtime).
 * Messages out: {type: "loaded", model, delegate} | {type: "failed", error}
 *               {type: "result", id, result: {landmarks, worldLandmarks} | null (no landmarker yet, or it failed)} */
let vision = null, fileset = null, landmarker = null, image = false;

async function load({ base, model, delegates, mode }) {
  if (!vision) vision = await import(base + "/vision_bundle.mjs");
  if (!fileset) fileset = await vision.FilesetResolver.forVisionTasks(base + "/wasm", true);  // the module build
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
  return { type: "failed", error: String(last || "no delegate") };
}

function detect({ id, frame, ms }) {
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

self.onmessage = async ({ data }) => {
  if (data.type === "load") {
    let out;
    try { out = await load(data); } catch (err) { out = { type: "failed", error: String(err) }; }
    self.postMessage(out);
  } else if (data.type === "detect") self.postMessage(detect(data));
};
