/* The camera set page: consent -> camera permission -> placement check -> live count -> saved result, with the
 * landmarks buffered in the browser (CameraBuffer) and sent in order (CameraSender). The video stays on this
 * device; only landmarks are sent. Query: ?item=<plan item id>[&model=lite|full][&delegate=CPU|GPU]. */
"use strict";
(() => {
  const { api, el, exercises, exerciseName, kindMessage } = Coach;
  const T = CameraText;
  const $ = (id) => document.getElementById(id);
  const main = $("main");
  const pid = main.dataset.patientId;
  const query = new URLSearchParams(location.search);
  const FLUSH_MS = 100;        // a batch every 0.1 s: the count follows within a few tenths of a second
  const MAX_WAIT_MS = 1000;    // frames wait at most this long in memory before they go to the buffer
  const HOLD_MS = 1500;        // the placement must hold this long before counting starts
  const SETTLE_MS = 1500;      // after the target is reached, the return to rest is recorded too
  const STILL_END_S = 20;      // no movement for this long ends the set
  const LOST_MS = 1500;        // nobody followed for this long: "you left the picture"
  const SLOW_FPS = 10;
  const LIMIT = { world: 2.99, imageLo: -0.99, imageHi: 1.99, z: 9.99 };  // inside the server's limits

  let item = null, ex = null, name = "exercise", stream = null, phase = "loading";
  let endSteps = [], endFrom = 0;  // the set's end: [step, s after Stop] (CameraPage.state(): for tests and benchmarks)
  const endStep = (step) => endSteps.push([step, +((performance.now() - endFrom) / 1000).toFixed(2)]);
  let set = null, pending = [], lastFlush = 0, lastT = -1, count = 0, target = 0;
  let okSince = null, lastSeen = 0, prevCentre = null, luma = null, lumaAt = 0, targetAt = null;
  const by = { one: 0, two: 0 };  // frames answered by each landmarker of the watch (camera_pose_core.js)
  const costs = [], COSTS = 300;  // the last frames' timing (cost())
  let answeredAt = null;  // when the landmarker's last answer came back (performance.now(), ms)
  let shown = null, grabbedShown = null;  // the camera frames shown so far (video frame callback), at the last grab
  let sent = 0, received = 0;  // frames this page handed to the sender; the set's frames the server holds (its answer)
  let stamps = [], placementSince = 0, slowSaid = false, lastVideoTime = -1, skipEvery = 1, frameNo = 0, detecting = false;
  const lumCanvas = document.createElement("canvas");

  function show(id) {
    for (const s of ["cam-consent", "cam-problem", "cam-resume", "cam-stage", "cam-result"]) $(s).hidden = s !== id;
  }
  function status(text, level) { const s = $("cam-status"); s.textContent = text; s.dataset.level = level || ""; }
  function say(text, level) { const s = $("cam-say"); if (s.textContent !== text) s.textContent = text; s.dataset.level = level || ""; }
  function note(text) { $("cam-note").textContent = text || ""; }
  /** Shows the problem card: its heading (title: what failed, CameraText), the sentence, "Save what I did" when a
   *  set's frames are kept (canSave). */
  function problem(text, canSave, title = T.wentWrong) {
    show("cam-problem"); $("cam-problem-h").textContent = title; $("cam-problem-text").textContent = text; status(text, "bad");
    if ($("cam-main-status")) $("cam-main-status").textContent = "problem";
    $("cam-problem-save").hidden = !canSave;
  }

  // ------------------------------------------------------------------ camera

  function cameraError(err) {
    const n = err && err.name;
    if (n === "NotAllowedError" || n === "SecurityError" || n === "PermissionDeniedError") return T.denied;
    if (n === "NotFoundError" || n === "OverconstrainedError" || n === "DevicesNotFoundError") return T.noCamera;
    if (n === "NotReadableError" || n === "AbortError" || n === "TrackStartError") return T.busy;
    return T.cameraFailed;
  }

  async function startCamera() {
    if (!navigator.mediaDevices || !navigator.mediaDevices.getUserMedia) { problem(T.noCameraApi, false, T.cannotStart); return false; }
    status(T.loading);
    try {
      stream = await navigator.mediaDevices.getUserMedia({ audio: false,
        video: { width: { ideal: 640 }, height: { ideal: 480 }, facingMode: "user" } });
    } catch (err) { problem(cameraError(err), Boolean(set), T.cannotStart); return false; }
    for (const track of stream.getVideoTracks()) track.addEventListener("ended", unplugged);
    const video = $("cam-video");
    video.srcObject = stream;
    await video.play().catch(() => {});
    return true;
  }

  function stopCamera() {
    if (stream) for (const track of stream.getTracks()) { track.removeEventListener("ended", unplugged); track.stop(); }
    stream = null;
  }

  function unplugged() {
    if (phase === "ending" || phase === "result") return;
    flush();
    stopCamera();
    phase = "problem";
    problem(T.unplugged, Boolean(set), T.cameraStopped);
  }

  /** The landmarker stopped and could not be started again (camera_pose.js): said, and what was done can be saved. */
  function trackerLost() {
    if (!looking()) return;
    flush();
    stopCamera();
    phase = "problem";
    problem(T.trackerFailed, Boolean(set));
  }

  async function loadTracker() {
    status(T.loadingModel);
    const model = query.get("model") || (navigator.hardwareConcurrency >= 4 ? "full" : "lite");
    const only = query.get("delegate") ? query.get("delegate").toUpperCase() : null;
    try { await CameraPose.load(model === "full" ? "full" : "lite", only); }
    catch (err) { console.error(err); problem(T.trackerFailed); return false; }
    return true;
  }

  // ------------------------------------------------------------------ the frame loop

  function schedule() {
    const video = $("cam-video");
    if (video.requestVideoFrameCallback) video.requestVideoFrameCallback(loop); else requestAnimationFrame(loop);
  }

  function fps(now) {
    stamps.push(now);
    while (stamps.length && now - stamps[0] > 3000) stamps.shift();
    return stamps.length > 1 ? (stamps.length - 1) / ((now - stamps[0]) / 1000) : null;
  }

  function looking() { return phase === "placement" || phase === "counting"; }

  /** Called on each new camera frame (video frame callback; else each animation frame): sends the frame to the
   *  landmarker when it is free (grab()). */
  function loop(_now, meta) {
    if (!looking()) return;
    if (meta) shown = meta.presentedFrames;
    grab();
    schedule();
  }

  /** Sends the newest video frame to the landmarker (in its worker) when it is not busy with the one before and the
   *  frame is one it has not seen; the result is handled when it comes back, and the main thread is free meanwhile
   *  (answers, count, drawing). When the answer comes back the next frame is sent at once if the camera has given
   *  one meanwhile: the landmarker then waits for no camera frame (it waited 21 ms of a 63 ms frame at the median,
   *  bench/README.md "Where a camera frame's time goes"). */
  function grab() {
    const video = $("cam-video");
    const now = performance.now();
    const fresh = shown !== null ? shown !== grabbedShown : video.currentTime !== lastVideoTime;
    if (!detecting && video.readyState >= 2 && fresh && !document.hidden && (frameNo++ % skipEvery === 0)) {
      lastVideoTime = video.currentTime; grabbedShown = shown;
      const taken = Date.now(), grabbedIn = phase, idle = answeredAt === null ? null : now - answeredAt;
      detecting = true;
      CameraPose.detect(video, now)  // a frame of the placement is not counted (it is older than the set's clock)
        .then((result) => {
          answeredAt = performance.now();
          if (!result || phase !== grabbedIn) return;
          onResult(video, result, taken, now);
          cost({ ...result.took, idle_ms: idle, page_ms: performance.now() - answeredAt });
        })
        .catch((err) => { console.error(err); trackerLost(); })
        .finally(() => { detecting = false; if (looking()) grab(); });
    }
  }

  /** Keeps the last COSTS frames' timing (ms, for bench/camera_page.py): idle (from the answer before to this
   *  frame's grab: the page's handling of that answer, then the wait for a camera frame), grab (the frame copied),
   *  trip (sent to answered), detect_ms and look_ms (the worker's detection, `two`'s look in it), page (the
   *  answer's handling and drawing). */
  function cost(row) { costs.push(row); if (costs.length > COSTS) costs.shift(); }

  function onResult(video, result, taken, now) {
    const rate = fps(now);
    if (result.by in by) by[result.by]++;
    if (now - lumaAt > 1000) { luma = CameraChecks.luminance(video, lumCanvas); lumaAt = now; }
    const idx = CameraChecks.pick(result, phase === "counting" ? prevCentre : null);
    const image = idx >= 0 ? result.landmarks[idx] : null;
    const world = idx >= 0 && result.worldLandmarks ? result.worldLandmarks[idx] : null;
    const poses = (result.landmarks || []).length;
    CameraPose.draw($("cam-overlay"), video, result, idx);
    if (phase === "placement") placementStep(image, world, poses, rate, now);
    else countingStep(image, world, poses, rate, taken, now);
  }

  async function checkSpeed(rate, now) {
    if (rate === null || now - placementSince < 3000 || rate >= SLOW_FPS || slowSaid) return;
    slowSaid = true;
    if (CameraPose.info.model === "full" && !query.get("model")) {
      phase = "loading";
      try { await CameraPose.load("lite", CameraPose.info.delegate); } catch (err) { problem(T.trackerFailed); return; }
      note(T.lighter); stamps = []; placementSince = performance.now(); slowSaid = false; phase = "placement"; schedule();
    } else { skipEvery = 1; note(T.slow); }
  }

  function placementStep(image, world, poses, rate, now) {
    const chk = CameraChecks.placement({ image, world, count: poses, luma, ex });
    $("cam-say").dataset.code = chk.code;
    if (!chk.ok) { okSince = null; say(chk.say, "warn"); checkSpeed(rate, now); return; }
    if (okSince === null) okSince = now;
    say(T.placementHold, "good");
    if (now - okSince >= HOLD_MS) beginCounting();
  }

  function clamp(v, lo, hi) { return Number.isFinite(v) ? Math.min(hi, Math.max(lo, v)) : null; }

  /** Returns the frame as the server takes it, or null when the landmarker gave a value that is not a number. */
  function frameOf(t, image, world) {
    const w = [], im = [], vis = [];
    for (let i = 0; i < 33; i++) {
      const a = world[i], b = image[i];
      const row = [clamp(a.x, -LIMIT.world, LIMIT.world), clamp(a.y, -LIMIT.world, LIMIT.world), clamp(a.z, -LIMIT.world, LIMIT.world)];
      const irow = [clamp(b.x, LIMIT.imageLo, LIMIT.imageHi), clamp(b.y, LIMIT.imageLo, LIMIT.imageHi), clamp(b.z, -LIMIT.z, LIMIT.z)];
      const v = clamp(b.visibility ?? a.visibility ?? 0, 0, 1);
      if (row.includes(null) || irow.includes(null) || v === null) return null;
      w.push(row.map((x) => +x.toFixed(4))); im.push(irow.map((x) => +x.toFixed(4))); vis.push(+v.toFixed(3));
    }
    return { t, world: w, image: im, visibility: vis };
  }

  function countingStep(image, world, poses, rate, taken, now) {
    if (image && world) {
      lastSeen = now;
      prevCentre = CameraChecks.centre(image);
      let t = (taken - set.t0_ms) / 1000;
      if (t <= lastT) t = lastT + 0.001;
      const f = frameOf(+t.toFixed(3), image, world);
      if (f) { pending.push(f); lastT = f.t; f._taken = taken; }
      if (luma !== null && luma < CameraChecks.DARK_LUMA) say(T.dark, "warn");
      else if (poses > 1) say(T.keptPatient, "warn");
      else if (CameraSender.isOffline()) say(T.offline, "warn");
      else say(set.hint ? T.hint(set.hint) : T.counting, set.hint ? "warn" : "");
    } else if (now - lastSeen > LOST_MS) {
      say(luma !== null && luma < CameraChecks.DARK_LUMA ? T.dark : poses > 0 ? T.keptPatient : T.leftFrame, "warn");
    }
    if (rate !== null && rate < SLOW_FPS && now - set.countingSince > 3000) note(T.slow);
    // a batch every FLUSH_MS while the server keeps up; when it is slower, the frames wait for the answer in flight
    // and go together (at most MAX_WAIT_MS), so the count never trails a queue of batches
    if (now - lastFlush >= FLUSH_MS && (CameraSender.idle() || now - lastFlush >= MAX_WAIT_MS)) flush(now);
  }

  function flush(now) {
    lastFlush = now || performance.now();
    if (!set || !pending.length) return;
    const taken = pending.map((f) => f._taken);
    const frames = pending.map(({ _taken, ...f }) => f);
    pending = [];
    sent += frames.length;
    const seq = set.next_seq++;
    const rate = stamps.length > 1 ? +((stamps.length - 1) / ((stamps[stamps.length - 1] - stamps[0]) / 1000)).toFixed(1) : null;
    const video = $("cam-video");
    const size = [video.videoWidth || 640, video.videoHeight || 480];
    set.taken = set.taken || {};
    set.taken[seq] = [taken[0], taken[taken.length - 1], Date.now()];
    CameraSender.add(seq, { seq, version: 1, image_size: size, frames, fps: rate }, { patientId: pid, state: set });
  }

  // ------------------------------------------------------------------ the set

  function renderCount() {
    $("cam-count").replaceChildren(el("span", { class: "n" }, count), el("span", { class: "of" }, T.countOf(target)));
    $("cam-count-spoken").textContent = T.countSpoken(count, target);
  }

  function onAnswer(out, body, timing) {
    if (out.count > count) { count = out.count; renderCount(); }
    received = Math.max(received, out.n_frames);
    const shown = Date.now();
    set.hint = out.hint;
    const taken = set.taken && set.taken[body.seq];
    if (taken) {  // for benchmarks (bench/camera_page.py): where the time from a frame to its count goes
      const [oldest, newest, flushed] = taken;
      window.dispatchEvent(new CustomEvent("coach-camera-count", { detail: { seq: body.seq, count: out.count,
        oldest_ms: shown - oldest, newest_ms: shown - newest, landmarker_ms: flushed - newest,
        buffer_ms: timing ? timing.sent - flushed : null, server_ms: timing ? timing.answered - timing.sent : null,
        draw_ms: timing ? shown - timing.answered : null } }));
      delete set.taken[body.seq];
    }
    if (phase !== "counting") return;
    if (count >= target && targetAt === null) { targetAt = performance.now(); setTimeout(() => endSet("target"), SETTLE_MS); }
    if (out.still_s >= STILL_END_S) endSet("still");
  }

  function onNetwork(up) {
    if (phase === "counting") say(up ? T.online : T.offline, up ? "good" : "warn");
    status(up ? T.online : T.offline, up ? "" : "warn");
    if (phase === "ending" && !up) status(T.savingOffline, "warn");
  }

  function onRefused(err) {
    console.error(err);
    if (phase === "counting") endSet("error");
  }

  function senderFor(s, fresh) {
    CameraSender.init(s.set_id, { answer: onAnswer, network: onNetwork, refused: onRefused,
      trouble: () => status(T.serverTrouble, "warn") }, fresh);
  }

  async function beginCounting() {
    if (phase !== "placement") return;
    phase = "starting";
    const fresh = !set;
    try {
      if (!set) {
        const model = "pose_landmarker_" + CameraPose.info.model;
        const out = await api("/camera/sets", { method: "POST", body: { plan_item_id: item.id, model } });
        set = { set_id: out.set_id, item_id: item.id, t0_ms: Date.now(), next_seq: 0, target: out.target_reps,
          exercise_slug: out.exercise_slug, model };
        await CameraBuffer.putSet(pid, set);
      }
      senderFor(set, fresh);
    } catch (err) { phase = "placement"; problem(kindMessage(err)); return; }
    target = set.target;
    renderCount();
    set.countingSince = performance.now();
    lastSeen = performance.now();
    phase = "counting";
    $("cam-stage").classList.add("counting");
    $("cam-count-box").hidden = false; $("cam-anyway").hidden = true; $("cam-stop").hidden = false;
    $("cam-main-status").textContent = "counting";
    status(T.counting); say(T.placementOk, "good");
    schedule();
  }

  async function endSet(reason) {
    if (!set || phase === "ending" || phase === "result") return;
    phase = "ending";
    $("cam-main-status").textContent = "ending";
    flush();
    set.ended = reason;
    endFrom = performance.now(); endSteps = []; endStep("buffer");
    await CameraBuffer.putSet(pid, set);
    stopCamera();
    $("cam-stop").hidden = true;
    status(CameraSender.isOffline() ? T.savingOffline : T.saving, CameraSender.isOffline() ? "warn" : "");
    say(T.saving);
    senderFor(set);
    let row = null;
    for (let attempt = 0; ; attempt++) {
      try {
        endStep(`drain ${attempt}`);
        await CameraSender.drain();
        endStep(`end ${attempt}`);
        row = await api(`/camera/sets/${set.set_id}/end`, { method: "POST", body: { last_seq: set.next_seq - 1, reason } });
        break;
      } catch (err) {
        endStep(`failed ${attempt}: ${err.status} ${err.error || err} ${err.detail || err.message || ""}`);
        if (err.status === 0 || err.status >= 500 || (err.error === "BatchOutOfOrder" && attempt < 5)) {
          status(err.status === 0 ? T.savingOffline : T.saving, "warn");
          await new Promise((r) => setTimeout(r, 2000));
          continue;
        }
        problem(`${T.saveFailed} (${kindMessage(err)})`);
        return;
      }
    }
    endStep("result");
    await showResult(row, reason);
  }

  let feelingOf = null;  // the stored set asked about under the result (feeling.js: pain and effort)
  function drawFeeling() {
    const block = feelingOf === null ? null : Feeling.block(feelingOf);
    $("cam-feeling").replaceChildren(...(block ? [block] : []));
  }
  Feeling.listen(drawFeeling);
  /** Asks how the stored set felt, under its result. */
  function askFeeling(sessionId) { feelingOf = sessionId; drawFeeling(); }

  async function showResult(row, reason) {
    phase = "result";
    stopCamera();
    show("cam-result");
    $("cam-main-status").textContent = row.status;
    if (row.status !== "stored") {
      const why = row.failure === "too_short" ? T.tooShort : T.notSaved;
      $("cam-result-text").textContent = why; $("cam-result-more").textContent = "";
      status(why, "warn");
    } else {
      let session = null;
      try { session = await api(`/sessions/${row.session_id}`); } catch (err) { session = null; }
      const reps = session ? session.repetitions : null;
      // the set's last count is the stored one; when it differs from the one shown (a flickering label can run the
      // live count ahead; a slow page sees few pictures), the page says so rather than change the number silently
      $("cam-result-more").textContent = T.resultMore(reason, count, reps, row.target_reps, session && session.rom_deg);
      if (reps !== null) count = reps;
      $("cam-result-text").textContent = T.result(reps, row.target_reps);
      $("cam-result-text").dataset.sessionId = row.session_id;
      status(T.result(reps, row.target_reps));
      askFeeling(row.session_id);
    }
    await CameraBuffer.dropSet(pid, row.set_id);
    set = null;
  }

  // ------------------------------------------------------------------ start, resume, consent

  async function toPlacement() {
    show("cam-stage");
    $("cam-stage").classList.remove("counting");
    $("cam-count-box").hidden = true; $("cam-stop").hidden = true; $("cam-anyway").hidden = false;
    if (!(await startCamera())) return;
    if (!CameraPose.info.model && !(await loadTracker())) return;
    show("cam-stage");
    const view = CameraChecks.viewFor(ex) === "side" ? T.viewSide : T.viewFront;
    status(T.nameAndView(name, view));
    okSince = null; stamps = []; placementSince = performance.now(); prevCentre = null;
    phase = "placement";
    $("cam-main-status").textContent = "placement";
    schedule();
  }

  async function resume(saved) {
    let row;
    try { row = await api(`/camera/sets/${saved.set_id}`); }
    catch (err) {
      if (err.status === 404) { await CameraBuffer.dropSet(pid, saved.set_id); return false; }
      throw err;
    }
    set = saved;
    if (row.status !== "recording") { await showResult(row, saved.ended || "stop"); return true; }
    // the page sends a batch while it writes it to the buffer: after a crash the server may hold batches the buffer
    // missed, so the set goes on after the later of the two (camera_sender.js)
    set.next_seq = Math.max(set.next_seq, row.last_seq + 1);
    senderFor(set);
    CameraSender.pump();  // what the reload interrupted is sent at once
    if (saved.ended) { await endSet(saved.ended); return true; }
    const plan = await findItem(saved.item_id);
    if (plan) { item = plan.item; ex = plan.ex; name = plan.name; }
    target = set.target; count = 0;
    show("cam-resume");
    const seconds = Math.max(0, Math.round((Date.now() - set.t0_ms) / 1000));
    $("cam-resume-text").textContent = T.resumeText(seconds, name);
    status(T.resumeText(seconds, name), "warn");
    $("cam-main-status").textContent = "resume";
    return true;
  }

  async function findItem(itemId) {
    const [lib, plans] = await Promise.all([exercises(), api(`/patients/${pid}/plans?limit=20`)]);
    for (const p of plans.items) {
      const found = p.items.find((i) => String(i.id) === String(itemId));
      if (found) return { item: found, ex: lib[found.exercise_slug] || {}, name: exerciseName(lib, found.exercise_slug) };
    }
    return null;
  }

  async function consentThenCamera() {
    const consent = await api("/camera/consent");
    $("cam-withdraw").hidden = !consent.given;
    if (consent.given) { await toPlacement(); return; }
    show("cam-consent");
    status(T.readFirst);
    $("cam-main-status").textContent = "consent";
    $("cam-agree").onclick = async () => {
      try { await api("/camera/consent", { method: "POST", body: { consent_version: consent.consent_version } }); }
      catch (err) { problem(kindMessage(err)); return; }
      $("cam-withdraw").hidden = false;
      await toPlacement();
    };
  }

  async function init() {
    const hidden = el("span", { id: "cam-main-status", class: "sr-only", "data-testid": "phase" }, "loading");
    main.append(hidden);
    const saveBtn = el("button", { type: "button", class: "btn btn-big btn-quiet", id: "cam-problem-save", hidden: true }, T.saveWhatIDid);
    $("cam-problem").append(saveBtn);
    saveBtn.onclick = () => endSet("stop");
    $("cam-retry").onclick = () => (set && phase !== "result" ? toPlacementKeepingSet() : location.reload());
    $("cam-anyway").onclick = () => { if (phase === "placement") { okSince = -Infinity; beginCounting(); } };
    $("cam-stop").onclick = () => endSet("stop");
    $("cam-continue").onclick = () => toPlacement();
    $("cam-finish").onclick = () => endSet("stop");
    $("cam-withdraw").onclick = async () => { await api("/camera/consent", { method: "DELETE" }); location.assign(Coach.url("/patient")); };
    document.addEventListener("visibilitychange", () => {
      if (phase !== "counting") return;
      if (document.hidden) { flush(); status(T.hidden, "warn"); say(T.hidden, "warn"); }
      else { lastSeen = performance.now(); status(T.resumed); say(T.resumed, "good"); }
    });
    try {
      const saved = await CameraBuffer.getSet(pid);
      if (saved && (await resume(saved))) return;
      const found = await findItem(query.get("item"));
      if (!found) { problem(T.notInPlan); return; }
      ({ item, ex, name } = found);
      $("cam-title").textContent = name;
      await consentThenCamera();
    } catch (err) { problem(kindMessage(err)); }
  }

  async function toPlacementKeepingSet() { await toPlacement(); }

  init();
  window.CameraPage = { state: () => ({ phase, count, target, set_id: set && set.set_id, next_seq: set && set.next_seq,
    frames: sent, received, model: CameraPose.info, by: { ...by }, end: endSteps.slice(), sender: CameraSender.state(), costs: costs.slice(), fps: stamps.length > 1 ? (stamps.length - 1) / ((stamps[stamps.length - 1] - stamps[0]) / 1000) : null }) };
})();
