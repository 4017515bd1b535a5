/* What the camera sees, in plain words: the placement check before counting (whole body, distance, side or front
 * view, light, one person) and the faults during a set. Pure functions of the landmarker's result; no DOM.
 * Landmarks: BlazePose's 33 (image: x, y in 0..1 of the picture; world: metres about the hips). */
"use strict";
const CameraChecks = (() => {
  const T = CameraText;
  const VISIBLE = 0.5, EDGE = 0.02;
  const HEAD = [0], SHOULDERS = [11, 12], ELBOWS = [13, 14], WRISTS = [15, 16], HIPS = [23, 24], KNEES = [25, 26], ANKLES = [27, 28];
  const DARK_LUMA = 40;  // mean luminance 0..255 of the picture below which we ask for light
  // side view: exercises in the sagittal plane that move the legs (squat, sit-to-stand, knee extension, leg raises)
  const SIDE_PREFIXES = ["knee_flexion", "hip_flexion"];

  /** Returns "side" or "front": the view the exercise needs (ex: {plane, defining_angles}). */
  function viewFor(ex) {
    const legs = (ex.defining_angles || []).some((a) => SIDE_PREFIXES.some((p) => a.startsWith(p)));
    return ex.plane === "sagittal" && legs ? "side" : "front";
  }

  /** Returns the landmarks the exercise needs in the picture: the whole body for leg exercises, else the upper body. */
  function needsFor(ex) {
    const legs = (ex.defining_angles || []).some((a) => /^(knee|hip)_/.test(a));
    return legs ? [...HEAD, ...SHOULDERS, ...HIPS, ...KNEES, ...ANKLES] : [...HEAD, ...SHOULDERS, ...ELBOWS, ...WRISTS, ...HIPS];
  }

  function centre(image) { return [(image[23].x + image[24].x) / 2, (image[23].y + image[24].y) / 2]; }

  /** Returns the index of the pose to follow: the one nearest to where the patient was (prev: [x, y] or null),
   *  else the largest. Never jumps to another person while the patient stays in view. */
  function pick(result, prev) {
    const poses = result.landmarks || [];
    if (!poses.length) return -1;
    let best = 0, bestScore = Infinity;
    poses.forEach((p, i) => {
      const c = centre(p);
      const ys = p.map((l) => l.y);
      const score = prev ? Math.hypot(c[0] - prev[0], c[1] - prev[1]) : -(Math.max(...ys) - Math.min(...ys));
      if (score < bestScore) { bestScore = score; best = i; }
    });
    if (prev && bestScore > 0.25) return -1;  // only someone else is in view: not the patient
    return best;
  }

  function inView(l) { return (l.visibility ?? 1) >= VISIBLE && l.x >= EDGE && l.x <= 1 - EDGE && l.y >= EDGE && l.y <= 1 - EDGE; }

  /** Returns {ok, say, code} for one frame: the first problem in the order light, nobody, two people, parts out of
   *  view, distance, view, off centre. image/world: the followed pose's landmarks; count: poses found. */
  function placement({ image, world, count, luma, ex }) {
    if (luma !== null && luma !== undefined && luma < DARK_LUMA) return { ok: false, say: T.dark, code: "dark" };
    if (!image) return { ok: false, say: T.nobody, code: "nobody" };
    if (count > 1) return { ok: false, say: T.twoPeople, code: "two_people" };
    const needs = needsFor(ex);
    if (!needs.every((i) => inView(image[i]))) {
      const legs = needs.includes(27);
      return { ok: false, say: legs ? T.wholeBody : T.upperBody, code: "out_of_view" };
    }
    const ys = needs.map((i) => image[i].y);
    const span = Math.max(...ys) - Math.min(...ys);
    if (span > 0.92) return { ok: false, say: T.tooClose, code: "too_close" };
    if (span < (needs.includes(27) ? 0.4 : 0.25)) return { ok: false, say: T.tooFar, code: "too_far" };
    if (world) {
      const dx = Math.abs(world[11].x - world[12].x), dz = Math.abs(world[11].z - world[12].z);
      const side = dz > dx;
      if (viewFor(ex) === "side" && !side) return { ok: false, say: T.sideView, code: "view" };
      if (viewFor(ex) === "front" && side) return { ok: false, say: T.frontView, code: "view" };
    }
    const c = centre(image);
    if (c[0] < 0.2 || c[0] > 0.8) return { ok: false, say: T.offCentre, code: "off_centre" };
    return { ok: true, say: T.placementHold, code: "ok" };
  }

  /** Returns the mean luminance (0..255) of a small copy of the video frame, or null when it cannot be read. */
  function luminance(video, canvas) {
    try {
      const w = 32, h = 24;
      canvas.width = w; canvas.height = h;
      const g = canvas.getContext("2d", { willReadFrequently: true });
      g.drawImage(video, 0, 0, w, h);
      const d = g.getImageData(0, 0, w, h).data;
      let s = 0;
      for (let i = 0; i < d.length; i += 4) s += 0.299 * d[i] + 0.587 * d[i + 1] + 0.114 * d[i + 2];
      return s / (w * h);
    } catch (e) { return null; }
  }

  return { viewFor, needsFor, pick, placement, luminance, centre, DARK_LUMA };
})();
