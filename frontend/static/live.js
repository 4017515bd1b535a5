/* The patient's live set: whether the home computer is ready, Start and Stop, the big count while it records, how
 * the set ended and its stored result. Events come through Coach.onChange (live=true); see backend/live. */
"use strict";
const Live = (() => {
  const { api, el, kindMessage } = Coach;
  const ANSWER_MS = 15000;  // a Start without any answer from the home computer for this long failed
  const ENDED = {
    target: "You reached your goal.",
    stop: "You stopped the set.",
    still: "The set ended because you did not move for a while.",
    limit: "The set reached its time limit.",
    source: "The recording ended.",
    error: "The recording stopped because of an error.",
  };
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
      timer = setTimeout(() => { if (current && current.starting && current.set_id === out.set_id) { current.failed = "The home computer did not answer. Please check it and try again."; render(); } }, ANSWER_MS);
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
    if (data.state === "failed") current.failed = data.hint || "The set could not be recorded.";
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
    if (!r) return el("p", { class: "lead", id: "live-saving" }, current.ended === "still" && current.count === 0 ? "Saving…" : "Saving your result…");
    if (r.error) return el("p", { class: "lead" }, r.error);
    const reps = r.repetitions === null || r.repetitions === undefined ? "We could not count this set." : `Saved: ${r.repetitions} ${r.repetitions === 1 ? "repetition" : "repetitions"}`;
    const rom = r.rom_deg ? `, moving through ${Math.round(r.rom_deg)} degrees.` : ".";
    return el("p", { class: "lead", id: "live-result" }, r.repetitions === null || r.repetitions === undefined ? reps : reps + rom);
  }

  function panel() {
    const c = current;
    const title = el("h2", { id: "live-h" }, names(c.slug) + (c.label ? ` — ${c.label}` : ""));
    if (c.failed) return [title, el("p", { class: "big-sentence", id: "live-failed" }, c.failed), closeButton()];
    if (c.lost) return [title, el("p", { class: "big-sentence", id: "live-lost" }, "Your home computer stopped during the set."),
      el("p", { class: "lead" }, "What you did so far is kept when it is at least 5 seconds long. It will show here once the computer is back on."),
      closeButton()];
    if (c.starting) return [title, el("p", { class: "big-sentence", id: "live-starting" }, "Starting… Please stand in front of the camera.")];
    const count = el("p", { class: "live-count", id: "live-count", "aria-hidden": "true" },
      el("span", { class: "n" }, c.count), el("span", { class: "of" }, ` of ${c.target}`));
    const spoken = el("p", { class: "sr-only", "aria-live": "polite" }, `${c.count} of ${c.target}`);
    if (c.ended) {
      const done = c.count >= c.target ? `You did all ${c.target} — well done!` : `You did ${c.count} of ${c.target}. Good effort!`;
      return [title, count, el("p", { class: "big-sentence", id: "live-ended" }, `Set finished. ${done}`),
        el("p", { class: "lead" }, ENDED[c.ended] || ""), resultBlock(), closeButton()];
    }
    const angle = c.angle === null || c.angle === undefined ? null : el("p", { class: "lead", id: "live-angle" }, `Angle now: ${Math.round(Math.abs(c.angle))} degrees`);
    const hint = c.hint ? el("p", { class: "live-hint", id: "live-hint", role: "status" }, c.hint) : null;
    return [title, count, spoken, angle, hint,
      el("button", { class: "btn btn-big btn-bad", id: "live-stop", type: "button", disabled: c.stopping || !c.set_id }, c.stopping ? "Stopping…" : "Stop")];
  }

  function closeButton() { return el("button", { class: "btn btn-big btn-quiet", id: "live-close", type: "button" }, "Close"); }

  function render() {
    const line = document.getElementById("agent-status");
    const words = {
      online: "Your home computer is ready. Press Start next to an exercise when you are in front of the camera.",
      offline: "Your home computer is not connected right now, so you cannot start an exercise from here. Please check that it is switched on and connected to the internet. This page notices by itself when it is back.",
      unpaired: "No home computer with a depth camera is set up for you. If this computer has a camera, press \"Start with this computer's camera\" next to an exercise.",
      unknown: "Checking your home computer…",
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
