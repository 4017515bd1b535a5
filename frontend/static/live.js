/* The patient's live set: whether the home computer is ready, Start and Stop, the big count while it records, how
 * the set ended and its stored result. Events come through Coach.onChange (live=true); see backend/live. */
"use strict";
const Live = (() => {
  const { api, el, kindMessage } = Coach;
  const ANSWER_MS = 15000;  // a Start without any answer from the home computer for this long failed
  const ENDED = {
    target: I18n.t("You reached your goal."),
    stop: I18n.t("You stopped the set."),
    still: I18n.t("The set ended because you did not move for a while."),
    limit: I18n.t("The set reached its time limit."),
    source: I18n.t("The recording ended."),
    error: I18n.t("The recording stopped because of an error."),
    cut: I18n.t("The set was cut short. What you did before it stopped is saved."),
  };
  // the home computer's hints (kinect_agent/analysis/live.py HINT_*), shown in the page's language by I18n.t(hint)
  const AGENT_HINTS = [
    I18n.N_("You are out of view: please step in front of the camera."), I18n.N_("Step back a little."),
    I18n.N_("Come a little closer."), I18n.N_("Move to the middle of the picture."),
    I18n.N_("The camera cannot see your arms well."), I18n.N_("The camera cannot see your legs well."),
  ];
  const SAVE_MS = 45000;  // an ended set whose stored result has not come for this long: said so, with Close
  const CONFIRM_MS = 3000;  // after the server came back: how often the agent's presence is asked until it is heard
  const FRAMES_MS = 3000;  // a recording set without a progress message for this long: the camera sends no pictures
  const RECENT_UPLOAD_MS = 2 * 86400000;  // a computer that uploaded within this long works, even when not live
  let pid = null, names = (slug) => slug, agent = "unknown", current = null, timer = null, howTo = (slug) => "";
  let lastUpload = null, dropped = false;  // the newest stored session's upload time; the agent left while watched
  // events that can overtake the answers they depend on: a set's progress heard before the answer to Start gave its
  // id, a stored session heard before the progress that names it; kept until that answer comes
  let early = [], storedEarly = null;

  function init(patientId, exerciseName, instructions) {
    pid = patientId; names = exerciseName; howTo = instructions || howTo;
    document.getElementById("live").addEventListener("click", (e) => {
      if (e.target.id === "live-stop") stop();
      if (e.target.id === "live-close") { current = null; render(); window.dispatchEvent(new CustomEvent("coach-live-closed")); }
    });
    if (typeof Feeling !== "undefined") Feeling.listen(render);
    Connection.listen((state, was) => {
      // back from a lost connection: what was known of the home computer is old until the server is asked again
      if (state === "ok" && was === "lost") { confirm = {}; agent = "unknown"; status(); resync(); }
      if (state === "lost" && running()) speak(SERVER_LOST);
      render();
    });
    setInterval(watchFrames, 500);
    return status();
  }

  /** Says when the camera stopped sending pictures mid-set (no progress for FRAMES_MS while all else is up). */
  function watchFrames() {
    if (!running() || current.starting || !current.heard_at || Connection.state !== "ok") return;
    const silent = Date.now() - current.heard_at > FRAMES_MS;
    if (silent !== Boolean(current.no_frames)) { current.no_frames = silent; render(); if (silent) speak(CAMERA_SILENT); }
  }

  /** After the connection came back: a set that ended meanwhile is shown with its stored result. */
  function resync() {
    const c = current;
    if (!c || !running()) return;
    setTimeout(async () => {
      if (current !== c || !running() || Date.now() - (c.heard_at || 0) < FRAMES_MS) return;  // it still runs
      try {
        const latest = (await api(`/sessions?patient_id=${pid}&limit=5`)).items;
        const stored = latest.find((s) => c.session_id && s.client_session_id === c.session_id);
        if (stored) { c.ended = "source"; c.result = stored; }
        else { c.failed = I18n.t("We lost track of this set while the connection was gone. If it was recorded, it shows under \u201cYour last exercise\u201d."); c.cut = true; }
      } catch (err) { c.failed = kindMessage(err); }
      render();
    }, FRAMES_MS);
  }

  /** The newest stored session's upload time (ISO), from the page's data: a computer that uploads works. */
  function uploaded(createdAt) { lastUpload = createdAt; render(); }

  /** After the server came back, "online" is believed only once the agent is heard anew (a live.agent event, or
   *  its last_seen_at moving on): a server that stopped leaves its agents' streams recorded as open for a while. */
  let confirm = null, confirmTimer = null, agentEvents = 0;  // live.agent events heard so far

  async function status() {
    if (pid === null) return;  // the event stream opened before init(): init() asks itself
    let out = null;
    const asked = agentEvents;
    try { out = await api(`/live/status?patient_id=${pid}`); } catch (err) { out = { state: "unknown" }; }
    if (agentEvents !== asked) return;  // a live.agent event came while asking: it is newer than this answer
    clearTimeout(confirmTimer);
    agent = out.state;
    if (confirm && agent === "online") {
      if (confirm.seen === undefined) confirm.seen = out.last_seen_at;
      if (out.last_seen_at === confirm.seen) { agent = "unknown"; confirmTimer = setTimeout(status, CONFIRM_MS); }
      else confirm = null;
    } else confirm = null;
    if (agent === "online") dropped = false;
    render();
  }

  function running() { return current && !current.ended && !current.failed && !current.lost; }

  async function start(item, label) {
    if (running()) return;
    current = { item, label, slug: item.exercise_slug, target: item.repetitions, starting: true, count: 0 };
    render();
    into_view();
    speak([names(current.slug) + " — " + label, firstInstruction(current.slug)].filter(Boolean).join(". "));
    try {
      const out = await api("/live/start", { method: "POST", body: { plan_item_id: item.id } });
      current.set_id = out.set_id;
      clearTimeout(timer);
      timer = setTimeout(() => { if (current && current.starting && current.set_id === out.set_id) { current.failed = I18n.t("The home computer did not answer. Please check it and try again."); render(); } }, ANSWER_MS);
      const heard = early.filter((data) => data.set_id === out.set_id);
      early = [];
      heard.forEach(onProgress);
    } catch (err) {
      if (err.status === 409) { agent = "offline"; current = null; } else current.failed = kindMessage(err);
    }
    render();
  }

  async function stop() {
    if (!current || !current.set_id) return;
    current.stopping = true; render();
    try { await api("/live/stop", { method: "POST", body: { set_id: current.set_id } }); }
    catch (err) { current.stopping = false; current.failed = kindMessage(err); render(); }
  }

  function onAgent(data) {
    agentEvents += 1;
    confirm = null; clearTimeout(confirmTimer);
    agent = data.online ? "online" : "offline";
    dropped = !data.online;
    if (!data.online && running()) { current.lost = true; current.cut = true; speak(I18n.t("Your home computer stopped during the set.")); }
    render();
  }

  function onCommand(data) {  // a Start pressed in another window of the same patient
    if (data.action === "start" && !running()) {
      current = { set_id: data.set_id, slug: data.exercise_slug, target: data.target_reps, starting: true, count: 0 };
      render();
      into_view();
    }
  }

  function onProgress(data) {
    if (current && current.starting && !current.set_id) { early.push(data); return; }  // before Start's answer
    if (data.state === "starting") {  // the home computer heard Start and readies the set: it answered
      if (current && current.starting && current.set_id === data.set_id) clearTimeout(timer);
      return;
    }
    if (!current || current.set_id !== data.set_id) {
      if (data.state !== "recording") return;
      current = { set_id: data.set_id, slug: data.exercise_slug, target: data.target, count: 0 };  // page opened mid-set
      into_view();
    }
    clearTimeout(timer);
    const before = current.starting ? 0 : current.count;
    Object.assign(current, { starting: false, count: data.count, target: data.target || current.target, angle: data.angle_deg,
      hint: data.hint, session_id: data.session_id, elapsed: data.elapsed_s, lost: false, heard_at: Date.now(), no_frames: false });
    if (data.state === "ended" && !current.ended) {
      current.ended = data.reason || "source";
      const c = current;
      setTimeout(() => {
        if (c.result) return;
        c.result = { error: I18n.t("Your home computer is still sending the result. It shows under \u201cYour last exercise\u201d once it is saved.") };
        if (current === c) render();
      }, SAVE_MS);
    }
    if (storedEarly && storedEarly.client_session_id === current.session_id) { const d = storedEarly; storedEarly = null; onStored(d); }
    if (data.state === "failed") { current.failed = data.hint ? I18n.t(data.hint) : I18n.t("The set could not be recorded."); speak(current.failed); }
    render();
    speakChanges(current, before);
    if (data.sent_at) window.dispatchEvent(new CustomEvent("coach-live-shown", { detail: { sent_at: data.sent_at, count: data.count } }));
  }

  async function onStored(data) {
    if (!current || !current.session_id || data.client_session_id !== current.session_id) {
      if (running()) storedEarly = data;  // its set's progress may not have been heard yet
      return;
    }
    const c = current;
    try { c.result = await api(`/sessions/${data.session_id}`); } catch (err) { c.result = { error: kindMessage(err) }; }
    if (c.cut && !c.result.error) {  // the part kept of a set cut short (agent stopped, connection lost) came: it is the set's end
      Object.assign(c, { cut: false, lost: false, failed: null, ended: c.ended || "cut" });
    }
    if (current !== c) return;
    render();
    speakChanges(current, current.count);
  }

  /** Returns whether the stored result has a count (then it is the set's count: the live count is brought level). */
  function counted(r) { return Boolean(r) && !r.error && r.repetitions !== null && r.repetitions !== undefined; }

  /** Returns the set's end in one sentence (shown, and spoken: voice.js), from the stored count once it is there. */
  function endSentence(c) {
    if (!c.result) return I18n.t("Set finished. Saving your result…");
    if (c.result.error) return I18n.t("Set finished.");
    if (!counted(c.result)) return I18n.t("Set finished. We could not count this set.");
    const n = c.result.repetitions;
    return n >= c.target ? I18n.t("Set finished. You did all {goal} — well done!", { goal: c.target })
      : I18n.t("Set finished. You did {done} of {goal}. Good effort!", { done: n, goal: c.target });
  }

  const CAMERA_SILENT = I18n.t("No pictures are coming from your camera. Please check that it is plugged in and that nothing covers it. The count goes on by itself when the pictures are back.");
  const SERVER_LOST = I18n.t("The connection to the server is lost. Your home computer goes on recording; the count shows again when the connection is back.");

  /** Speaks a text the panel shows (voice.js; nothing when the voice is off or the page has no Voice). */
  function speak(text) { if (typeof Voice !== "undefined" && text) Voice.say(text); }

  /** Returns the first sentence of the exercise's instructions (the library's, in the page's language). */
  function firstInstruction(slug) {
    const text = (howTo(slug) || "").trim();
    const m = text.match(/^.*?[.!?](\s|$)/);
    return (m ? m[0] : text).trim();
  }

  /** Returns the encouragement for a count: halfway, and before the last repetition ("" for none). */
  function cheer(count, target) {
    const half = Math.floor(target / 2);
    if (count === target - 1 && target >= 2) return I18n.t("One more — the last one!");
    if (count === half && half >= 2 && half < target - 1) return I18n.t("Halfway there — keep going!");
    return "";
  }

  /** Says what changed in the set: the counts as they rise, the encouragement, the end sentence once. */
  function speakChanges(c, before) {
    if (c.ended) {
      const words = endSentence(c);
      if (c.result && c.said_end !== words) { c.said_end = words; speak(words); }
      return;
    }
    if (c.count > before && !c.starting) {
      speak(String(c.count));
      const more = cheer(c.count, c.target);
      if (more) speak(more);
    }
  }

  /** Returns why the set ended, in words; "" for a goal the live count reached but the stored count did not (the end
   *  sentence gives the stored count: "You reached your goal" beside "You did 8 of 10" would contradict it). */
  function whyEnded(c) {
    if (c.ended === "target" && counted(c.result) && c.result.repetitions < c.target) return "";
    return ENDED[c.ended] || "";
  }

  function resultBlock() {
    const r = current.result;
    if (!r) return null;
    if (r.error) return el("p", { class: "lead" }, r.error);
    if (!counted(r)) return el("p", { class: "lead", id: "live-result" }, I18n.t("Saved. Please make sure the camera can see all of you next time."));
    return el("p", { class: "lead", id: "live-result" }, r.rom_deg ? I18n.t("Saved, moving through {rom} degrees.", { rom: Math.round(r.rom_deg) }) : I18n.t("Saved."));
  }

  function panel() {
    const c = current;
    const title = el("h2", { id: "live-h" }, names(c.slug) + (c.label ? " — " + c.label : ""));
    if (c.failed) return [title, el("p", { class: "big-sentence", id: "live-failed" }, c.failed), closeButton()];
    if (c.lost) return [title, el("p", { class: "big-sentence", id: "live-lost" }, I18n.t("Your home computer stopped during the set.")),
      el("p", { class: "lead" }, I18n.t("What you did so far is kept when it is at least 5 seconds long. It will show here once the computer is back on.")),
      closeButton()];
    const offline = Connection.state === "lost" ? el("p", { class: "live-hint", id: "live-offline", role: "alert" },
      I18n.t("The connection to the server is lost. Your home computer goes on recording; the count shows again when the connection is back.")) : null;
    const first = firstInstruction(c.slug);
    const how = first ? el("p", { class: "lead", id: "live-instruction" }, first) : null;
    if (c.starting) return [title, el("p", { class: "big-sentence", id: "live-starting" }, I18n.t("Starting… Please stand in front of the camera.")), how, offline];
    const shown = c.ended && counted(c.result) ? c.result.repetitions : c.count;  // the stored count once it is there
    const count = el("p", { class: "live-count", id: "live-count", "aria-hidden": "true" },
      el("span", { class: "n" }, shown), el("span", { class: "of" }, " " + I18n.t("of {goal}", { goal: c.target })));
    if (c.ended) {
      return [title, c.result && !counted(c.result) ? null : count, el("p", { class: "big-sentence", id: "live-ended", role: "status" }, endSentence(c)),
        el("p", { class: "lead", id: "live-why" }, whyEnded(c)), resultBlock(),
        c.result && c.result.id && typeof Feeling !== "undefined" ? Feeling.block(c.result.id) : null, c.result ? closeButton() : null];
    }
    const spoken = el("p", { class: "sr-only", "aria-live": "polite" }, I18n.t("{done} of {goal}", { done: shown, goal: c.target }));
    const angle = c.angle === null || c.angle === undefined ? null : el("p", { class: "lead", id: "live-angle" }, I18n.t("Angle now: {angle} degrees", { angle: Math.round(Math.abs(c.angle)) }));
    const camera = c.no_frames ? el("p", { class: "live-hint", id: "live-camera", role: "alert" },
      I18n.t("No pictures are coming from your camera. Please check that it is plugged in and that nothing covers it. The count goes on by itself when the pictures are back.")) : null;
    const hint = c.hint && !camera ? el("p", { class: "live-hint", id: "live-hint", role: "status" }, I18n.t(c.hint)) : null;  // the agent's hints are catalogue msgids
    const more = cheer(c.count, c.target);
    const encourage = more ? el("p", { class: "big-sentence", id: "live-cheer" }, more) : null;
    return [title, count, spoken, encourage, offline, camera, how, angle, hint,
      el("button", { class: "btn btn-big btn-bad", id: "live-stop", type: "button", disabled: c.stopping || !c.set_id || Boolean(offline) },
        c.stopping ? I18n.t("Stopping…") : I18n.t("Stop"))];
  }

  function closeButton() { return el("button", { class: "btn btn-big btn-quiet", id: "live-close", type: "button" }, I18n.t("Close")); }

  /** Brings the live panel to the top of the window (Start may be pressed far down the page). */
  function into_view() {
    const box = document.getElementById("live");
    if (!box.hidden) box.scrollIntoView({ block: "start", behavior: "instant" });
  }

  /** Returns the state of the home computer as shown: the server's state, "idle" when it is not live but uploads. */
  function shownState() {
    if (Connection.state === "lost") return "server-lost";
    if (agent === "offline" && !dropped && lastUpload && Date.now() - new Date(lastUpload) < RECENT_UPLOAD_MS) return "idle";
    return agent;
  }

  function render() {
    const line = document.getElementById("agent-status");
    const state = shownState();
    const words = {
      online: I18n.t("Your home computer is ready. Press Start next to an exercise when you are in front of the camera."),
      offline: I18n.t("Your home computer is not connected right now, so you cannot start an exercise from here. Please check that it is switched on and connected to the internet. This page notices by itself when it is back."),
      idle: lastUpload ? I18n.t("Your home computer sent your last exercise {day} at {time}. Do your exercises in front of it as usual: it sends them here by itself.",
        { day: Coach.plainDay(lastUpload), time: Coach.fmtTime(lastUpload) }) : "",
      "server-lost": I18n.t("This page cannot reach the server right now, so you cannot start an exercise from here. Please check that your internet is working. The page notices by itself when the connection is back."),
      unpaired: CameraEntry.available  // a camera-only patient: the camera links beside the exercises are the way
        ? I18n.t("Do your exercises with this computer's camera: press “{start}” next to an exercise.", { start: CameraEntry.LABEL })
        : I18n.t("No home computer is set up for you yet. Your therapist can help you set one up."),
      unknown: I18n.t("Checking your home computer…"),
    };
    line.textContent = words[state] || words.unknown;
    line.dataset.state = state;
    line.toggleAttribute("data-camera", state === "unpaired" && CameraEntry.available);
    for (const b of document.querySelectorAll("button.start")) {
      b.hidden = agent !== "online";
      b.disabled = Boolean(running()) || state === "server-lost";
    }
    const box = document.getElementById("live");
    box.hidden = !current;
    box.replaceChildren(...(current ? panel() : []).filter(Boolean));
  }

  return { init, status, render, start, uploaded, onAgent, onCommand, onProgress, onStored, get current() { return current; } };
})();
