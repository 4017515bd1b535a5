/* The pose landmarker in the page: MediaPipe Tasks Vision's WebAssembly and the pinned BlazePose model, both served
 * by the app from /static/vendor/mediapipe/ (nothing fetched from another site; the page's CSP allows
 * 'wasm-unsafe-eval' and connections to this origin only). GPU delegate when the browser gives one, else CPU.
 * The skeleton overlay is drawn here too. */
"use strict";
const CameraPose = (() => {
  const BASE = () => Coach.url("/static/vendor/mediapipe");
  const BONES = [[11, 12], [11, 13], [13, 15], [12, 14], [14, 16], [11, 23], [12, 24], [23, 24], [23, 25], [25, 27],
    [27, 31], [24, 26], [26, 28], [28, 32], [0, 11], [0, 12]];
  let vision = null, fileset = null, landmarker = null;
  const info = { model: null, delegate: null };

  /** Loads the landmarker with model "lite" or "full"; delegate "GPU" first unless only: "CPU". Throws on failure. */
  async function load(model, only) {
    if (!vision) vision = await import(BASE() + "/vision_bundle.mjs");
    if (!fileset) fileset = await vision.FilesetResolver.forVisionTasks(BASE() + "/wasm");
    if (landmarker) { landmarker.close(); landmarker = null; }
    let last = null;
    for (const delegate of only ? [only] : ["GPU", "CPU"]) {
      try {
        landmarker = await vision.PoseLandmarker.createFromOptions(fileset, {
          baseOptions: { modelAssetPath: `${BASE()}/pose_landmarker_${model}.task`, delegate },
          runningMode: "VIDEO", numPoses: 2, minPoseDetectionConfidence: 0.5, minPosePresenceConfidence: 0.5,
          minTrackingConfidence: 0.5, outputSegmentationMasks: false,
        });
        info.model = model; info.delegate = delegate;
        return info;
      } catch (err) { last = err; }
    }
    throw last || new Error("no delegate");
  }

  /** Returns the landmarker's result for the video's current frame ({landmarks, worldLandmarks}). */
  function detect(video, nowMs) { return landmarker.detectForVideo(video, nowMs); }

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
