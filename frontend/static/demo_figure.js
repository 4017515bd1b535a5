/* How each exercise of the plan is done, before Start: a looping stick figure of one repetition from the motion
 * library the simulator uses (GET /exercises/{slug}/demonstration: side view for movements in the sagittal plane,
 * front view otherwise), the library's instructions in the page's language, and the therapist's note. No camera
 * is needed. With "reduce motion" asked for by the system, the figure stands still at the repetition's peak. */
"use strict";
const Demo = (() => {
  const { api, el } = Coach;
  const SIZE = 180;  // CSS px of the square canvas
  const cache = new Map();  // slug -> Promise of the demonstration
  const figures = [];  // {canvas, demo} drawn by the one animation loop
  const still = window.matchMedia && window.matchMedia("(prefers-reduced-motion: reduce)").matches;
  let looping = false;

  function load(slug) {
    if (!cache.has(slug)) cache.set(slug, api(`/exercises/${encodeURIComponent(slug)}/demonstration`).catch(() => null));
    return cache.get(slug);
  }

  /** Returns the frame of the repetition's peak (the joint farthest from its first position). */
  function peak(frames) {
    let best = 0, far = -1;
    for (let k = 0; k < frames.length; k++) {
      let d = 0;
      for (let j = 0; j < frames[k].length; j++) d = Math.max(d, Math.hypot(frames[k][j][0] - frames[0][j][0], frames[k][j][1] - frames[0][j][1]));
      if (d > far) { far = d; best = k; }
    }
    return best;
  }

  const BACKREST_M = 0.45;  // the chair's backrest above the seat (side view)

  /** Draws the chair of a seated exercise (demo.seat, metres) behind the figure: seat, legs, backrest from the side. */
  function chair(ctx, demo, X, Y, dpr) {
    const { height: h, x0, x1 } = demo.seat;
    ctx.strokeStyle = "#a0a096"; ctx.lineWidth = 4 * dpr;
    ctx.beginPath();
    ctx.moveTo(X([x0, h]), Y([x0, h])); ctx.lineTo(X([x1, h]), Y([x1, h]));  // the seat
    for (const x of [x0, x1]) { ctx.moveTo(X([x, h]), Y([x, h])); ctx.lineTo(X([x, 0]), Y([x, 0])); }  // the legs
    if (demo.view === "side") { ctx.moveTo(X([x0, h]), Y([x0, h])); ctx.lineTo(X([x0, h + BACKREST_M]), Y([x0, h + BACKREST_M])); }
    ctx.stroke();
  }

  /** Draws frame k of demo on canvas: bones as thick lines, the head as a circle, the floor as a line, the chair. */
  function draw(canvas, demo, k) {
    const ctx = canvas.getContext("2d"), dpr = window.devicePixelRatio || 1, w = SIZE * dpr;
    if (canvas.width !== w) { canvas.width = w; canvas.height = w; }
    const f = demo.frames[k], box = demo.box;
    const scale = (w * 0.86) / Math.max(box.w, box.h), ox = w / 2 - scale * (box.x0 + box.w / 2), oy = w * 0.94;
    const X = (p) => ox + scale * p[0], Y = (p) => oy - scale * (p[1] - box.y0);
    ctx.clearRect(0, 0, w, w);
    ctx.lineCap = "round"; ctx.lineJoin = "round";
    ctx.strokeStyle = "#8a8a80"; ctx.lineWidth = 2 * dpr;
    ctx.beginPath(); ctx.moveTo(w * 0.05, oy + 2 * dpr); ctx.lineTo(w * 0.95, oy + 2 * dpr); ctx.stroke();
    if (demo.seat) chair(ctx, demo, X, Y, dpr);
    ctx.strokeStyle = "#0b4f9c"; ctx.lineWidth = 7 * dpr;
    for (const [a, b] of demo.bones) {
      if (demo.joints[b] === "HEAD") continue;
      ctx.beginPath(); ctx.moveTo(X(f[a]), Y(f[a])); ctx.lineTo(X(f[b]), Y(f[b])); ctx.stroke();
    }
    const head = f[demo.joints.indexOf("HEAD")], neck = f[demo.joints.indexOf("NECK")];
    const r = Math.max(6 * dpr, 0.6 * Math.hypot(X(head) - X(neck), Y(head) - Y(neck)));
    ctx.fillStyle = "#0b4f9c";
    ctx.beginPath(); ctx.arc(X(head), Y(head), r, 0, 2 * Math.PI); ctx.fill();
  }

  function tick(now) {
    for (const fig of figures) {
      if (!fig.canvas.isConnected) continue;
      const k = Math.floor(((now / 1000) * fig.demo.rate_hz) % fig.demo.frames.length);
      if (k !== fig.k) { fig.k = k; draw(fig.canvas, fig.demo, k); }
    }
    for (let i = figures.length - 1; i >= 0; i--) if (!figures[i].canvas.isConnected) figures.splice(i, 1);
    if (figures.length) requestAnimationFrame(tick); else looping = false;
  }

  /** Returns the block that shows how an exercise is done: the figure, the instructions, the therapist's note. */
  function block(item, exercise, name) {
    const canvas = el("canvas", { class: "demo-figure", width: SIZE, height: SIZE, role: "img",
      "aria-label": I18n.t("How to do {exercise}: a figure shows one repetition", { exercise: name }) });
    const view = el("p", { class: "demo-view muted" });
    const box = el("div", { class: "demo" }, el("div", { class: "demo-stage" }, canvas, view),
      el("div", { class: "demo-words" },
        el("p", { class: "demo-h" }, el("strong", {}, I18n.t("How to do it"))),
        exercise && exercise.instructions ? el("p", { class: "demo-instructions" }, exercise.instructions) : null,
        item.notes ? el("p", { class: "demo-note" }, el("strong", {}, I18n.t("From your therapist:") + " "), item.notes) : null));
    load(item.exercise_slug).then((demo) => {
      if (!demo || !demo.frames.length) { box.querySelector(".demo-stage").remove(); return; }
      const points = demo.frames.flat();
      if (demo.seat) points.push([demo.seat.x0, demo.seat.height + (demo.view === "side" ? BACKREST_M : 0)], [demo.seat.x1, 0]);
      const xs = points.map((p) => p[0]), ys = points.map((p) => p[1]);
      demo.box = { x0: Math.min(...xs), y0: Math.min(...ys), w: Math.max(...xs) - Math.min(...xs), h: Math.max(...ys) - Math.min(...ys) };
      view.textContent = demo.view === "side" ? I18n.t("Seen from the side") : I18n.t("Seen from the front, as in a mirror");
      canvas.dataset.frames = demo.frames.length;
      canvas.dataset.view = demo.view;
      draw(canvas, demo, peak(demo.frames));
      if (still) return;
      figures.push({ canvas, demo, k: -1 });
      if (!looping) { looping = true; requestAnimationFrame(tick); }
    });
    return box;
  }

  return { block };
})();
