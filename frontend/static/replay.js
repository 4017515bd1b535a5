/* Replay page: the session's facts from the API above viser's player (an iframe of this origin). */
"use strict";
(() => {
  const { api, exercises, exerciseName, fmtDateTime, showError } = Coach;
  const sid = document.getElementById("main").dataset.sessionId;
  const info = document.getElementById("replay-info");

  async function load() {
    try {
      const [lib, s] = await Promise.all([exercises(), api(`/sessions/${sid}`)]);
      const name = exerciseName(lib, s.exercise_slug);
      document.getElementById("replay-title").textContent = `${name} · ${fmtDateTime(s.started_at)}`;
      info.textContent = [s.repetitions === null ? I18n.t("— repetitions") : I18n.nt("{n} repetition", "{n} repetitions", s.repetitions),
        s.rom_deg === null ? null : I18n.t("range of motion {angle}°", { angle: I18n.number(s.rom_deg, 1) }),
        s.quality_ok === false ? I18n.t("poor data quality") : null, I18n.t("{seconds} s", { seconds: I18n.number(s.duration_s, 1) })].filter(Boolean).join(" · ");
    } catch (err) { info.textContent = ""; showError(err); }
  }
  load();

  // every recording (both skeletons, or one alone) is built by a worker: while it is prepared the page says so and
  // keeps showing what it showed, then plays the new one
  const viewer = document.getElementById("viewer");
  const stateBox = document.getElementById("replay-state");
  const POLL_MS = 1500;
  let wanted = "";  // the skeleton the checkboxes ask for alone ("raw", "filtered"), or "" for both
  // whole sentences per skeleton shown: "the replay" put into a shared sentence does not translate
  const PREPARING = { raw: I18n.N_("The 3D replay of the raw skeleton alone is being prepared."),
    filtered: I18n.N_("The 3D replay of the filtered skeleton alone is being prepared."), "": I18n.N_("The 3D replay is being prepared.") };
  const FAILED = { raw: I18n.N_("The 3D replay of the raw skeleton alone could not be prepared."),
    filtered: I18n.N_("The 3D replay of the filtered skeleton alone could not be prepared."), "": I18n.N_("The 3D replay could not be prepared.") };
  function say(kind, text) { stateBox.className = kind; stateBox.textContent = text; stateBox.hidden = false; }
  async function show(layer) {
    wanted = layer;
    const query = layer ? `?layer=${layer}` : "";
    let state;
    try {
      state = await api(`/sessions/${sid}/replay/state${query}`);
    } catch (err) {
      if (wanted !== layer) return;
      if (err.error === "SessionFileRemoved" || err.status === 404) {
        stateBox.hidden = true;
        showError(err);
        return;
      }
      say("alert", I18n.t("The replay's state could not be read ({reason}); trying again.", { reason: err.detail || err.message }));
      setTimeout(() => { if (wanted === layer) show(layer); }, POLL_MS * 2);
      return;
    }
    if (wanted !== layer) return;  // the checkboxes changed meanwhile
    if (state.state === "ready") {
      stateBox.hidden = true;
      viewer.src = Coach.url(`/replay/viewer/?playbackPath=${encodeURIComponent(viewer.dataset.recording + query)}`);
      viewer.hidden = false;
      return;
    }
    if (state.state === "failed") { say("alert", I18n.t(FAILED[layer]) + " " + state.detail); return; }
    say("note", I18n.t(PREPARING[layer]) + " " + state.detail);
    setTimeout(() => { if (wanted === layer) show(layer); }, POLL_MS);
  }
  if (viewer.hasAttribute("data-preparing")) show("");

  // the two checkboxes: both skeletons, or one alone (?layer=); at least one stays shown
  const boxes = [document.getElementById("show-filtered"), document.getElementById("show-raw")];
  const note = document.getElementById("layers-note");
  for (const box of boxes) {
    box.addEventListener("change", () => {
      const shown = boxes.filter((b) => b.checked).map((b) => b.value);
      if (!shown.length) { box.checked = true; note.textContent = I18n.t("At least one skeleton stays shown."); return; }
      note.textContent = "";
      show(shown.length === 1 ? shown[0] : "");
    });
  }
})();
