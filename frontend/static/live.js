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
  };
  // the home computer's hints (kinect_agent/analysis/live.py HINT_*), shown in the page's language by I18n.t(hint)
  const AGENT_HINTS = [
    I18n.N_("You are out of view: please step in front of the camera."), I18n.N_("Step back a little."),
    I18n.N_("Come a little closer."), I18n.N_("Move to the middle of the picture."),
    I18n.N_("The camera cannot see your arms well."), I18n.N_("The camera cannot see your legs well."),
  ];
  let pid = null, names = (slug) => slug, agent = "unknown", current = null, timer = null;

  function init(patientId, exerciseName) {
    pid = patientId; names = exerciseName;
    document.getElementById("live").addEventListener("click", (e) => {
      if (e.target.id === "live-stop") stop();
      if (e.target.id === "live-close") { current = null; render(); }
    });
    return status();
  }

  async function status() {
    if (pid === null) return;  // the event stream opened before init(): init() asks itself
    try { agent = (await api(`/live/status?patient_id=${pid}`)).state; } catch (err) { agent = "unknown"; }
    render();
  }

  function running() { return current && !current.ended && !current.failed && !current.lost; }

  async function start(item, label) {
    if (running()) return;
    current = { item, label, slug: item.exercise_slug, target: item.repetitions, starting: true, count: 0 };
    render();
    try {
      const out = await api("/live/start", { method: "POST", body: { plan_item_id: item.id } });
      current.set_id = out.set_id;
      clearTimeout(timer);
      timer = setTimeout(() => { if (current && current.starting && current.set_id === out.set_id) { current.failed = I18n.t("The home computer did not answer. Please check it and try again."); render(); } }, ANSWER_MS);
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
    agent = data.online ? "online" : "offline";
    if (!data.online && running()) current.lost = true;
    render();
  }

  function onCommand(data) {  // a Start pressed in another window of the same patient
    if (data.action === "start" && !running()) {
      current = { set_id: data.set_id, slug: data.exercise_slug, target: data.target_reps, starting: true, count: 0 };
      render();
    }
  }

  function onProgress(data) {
    if (!current || current.set_id !== data.set_id) {
      if (data.state !== "recording") return;
      current = { set_id: data.set_id, slug: data.exercise_slug, target: data.target, count: 0 };  // page opened mid-set
    }
    clearTimeout(timer);
    Object.assign(current, { starting: false, count: data.count, target: data.target || current.target, angle: data.angle_deg,
      hint: data.hint, session_id: data.session_id, elapsed: data.elapsed_s, lost: false });
    if (data.state === "ended") current.ended = data.reason || "source";
    if (data.state === "failed") current.failed = data.hint || I18n.t("The set could not be recorded.");
    render();
    if (data.sent_at) window.dispatchEvent(new CustomEvent("coach-live-shown", { detail: { sent_at: data.sent_at, count: data.count } }));
  }

  async function onStored(data) {
    if (!current || !current.session_id || data.client_session_id !== current.session_id) return;
    try { current.result = await api(`/sessions/${data.session_id}`); } catch (err) { current.result = { error: kindMessage(err) }; }
    render();
  }

  function resultBlock() {
    const r = current.result;
    if (!r) return el("p", { class: "lead", id: "live-saving" }, current.ended === "still" && current.count === 0 ? I18n.t("Saving…") : I18n.t("Saving your result…"));
    if (r.error) return el("p", { class: "lead" }, r.error);
    const reps = r.repetitions === null || r.repetitions === undefined ? I18n.t("We could not count this set.") : I18n.nt("Saved: {n} repetition", "Saved: {n} repetitions", r.repetitions);
    const rom = r.rom_deg ? I18n.t(", moving through {rom} degrees.", { rom: Math.round(r.rom_deg) }) : ".";
    return el("p", { class: "lead", id: "live-result" }, r.repetitions === null || r.repetitions === undefined ? reps : reps + rom);
  }

  function panel() {
    const c = current;
    const title = el("h2", { id: "live-h" }, names(c.slug) + (c.label ? " — " + c.label : ""));
    if (c.failed) return [title, el("p", { class: "big-sentence", id: "live-failed" }, c.failed), closeButton()];
    if (c.lost) return [title, el("p", { class: "big-sentence", id: "live-lost" }, I18n.t("Your home computer stopped during the set.")),
      el("p", { class: "lead" }, I18n.t("What you did so far is kept when it is at least 5 seconds long. It will show here once the computer is back on.")),
      closeButton()];
    if (c.starting) return [title, el("p", { class: "big-sentence", id: "live-starting" }, I18n.t("Starting… Please stand in front of the camera."))];
    const count = el("p", { class: "live-count", id: "live-count", "aria-hidden": "true" },
      el("span", { class: "n" }, c.count), el("span", { class: "of" }, " " + I18n.t("of {goal}", { goal: c.target })));
    const spoken = el("p", { class: "sr-only", "aria-live": "polite" }, I18n.t("{done} of {goal}", { done: c.count, goal: c.target }));
    if (c.ended) {
      const done = c.count >= c.target ? I18n.t("Set finished. You did all {goal} — well done!", { goal: c.target })
        : I18n.t("Set finished. You did {done} of {goal}. Good effort!", { done: c.count, goal: c.target });
      return [title, count, el("p", { class: "big-sentence", id: "live-ended" }, done),
        el("p", { class: "lead" }, ENDED[c.ended] || ""), resultBlock(), closeButton()];
    }
    const angle = c.angle === null || c.angle === undefined ? null : el("p", { class: "lead", id: "live-angle" }, I18n.t("Angle now: {angle} degrees", { angle: Math.round(Math.abs(c.angle)) }));
    const hint = c.hint ? el("p", { class: "live-hint", id: "live-hint", role: "status" }, I18n.t(c.hint)) : null;  // the agent's hints are catalogue msgids
    return [title, count, spoken, angle, hint,
      el("button", { class: "btn btn-big btn-bad", id: "live-stop", type: "button", disabled: c.stopping || !c.set_id }, c.stopping ? I18n.t("Stopping…") : I18n.t("Stop"))];
  }

  function closeButton() { return el("button", { class: "btn btn-big btn-quiet", id: "live-close", type: "button" }, I18n.t("Close")); }

  function render() {
    const line = document.getElementById("agent-status");
    const words = {
      online: I18n.t("Your home computer is ready. Press Start next to an exercise when you are in front of the camera."),
      offline: I18n.t("Your home computer is not connected right now, so you cannot start an exercise from here. Please check that it is switched on and connected to the internet. This page notices by itself when it is back."),
      unpaired: I18n.t("No home computer with a depth camera is set up for you. If this computer has a camera, press \"Start with this computer's camera\" next to an exercise."),
      unknown: I18n.t("Checking your home computer…"),
    };
    line.textContent = words[agent] || words.unknown;
    line.dataset.state = agent;
    for (const b of document.querySelectorAll("button.start")) {
      b.hidden = agent !== "online";
      b.disabled = Boolean(running());
    }
    const box = document.getElementById("live");
    box.hidden = !current;
    box.replaceChildren(...(current ? panel() : []).filter(Boolean));
  }

  return { init, status, render, start, onAgent, onCommand, onProgress, onStored };
})();
