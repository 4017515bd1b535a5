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
      info.textContent = [`${s.repetitions === null ? "—" : s.repetitions} repetitions`,
        s.rom_deg === null ? null : `range of motion ${s.rom_deg.toFixed(1)}°`,
        s.quality_ok === false ? "poor data quality" : null, `${s.duration_s.toFixed(1)} s`].filter(Boolean).join(" · ");
    } catch (err) { info.textContent = ""; showError(err); }
  }
  load();

  // the recording is built by a worker: while it is prepared the page says so, then loads again with the player
  const viewer = document.getElementById("viewer");
  const stateBox = document.getElementById("replay-state");
  const POLL_MS = 1500;
  async function waitForRecording() {
    let state;
    try {
      state = await api(`/sessions/${sid}/replay/state`);
    } catch (err) {
      if (err.error === "SessionFileRemoved" || err.status === 404) {
        stateBox.hidden = true;
        showError(err);
        return;
      }
      stateBox.className = "alert";
      stateBox.textContent = `The replay's state could not be read (${err.detail || err.message}); trying again.`;
      stateBox.hidden = false;
      setTimeout(waitForRecording, POLL_MS * 2);
      return;
    }
    if (state.state === "ready") { location.reload(); return; }
    if (state.state === "failed") {
      stateBox.className = "alert";
      stateBox.textContent = `The 3D replay could not be prepared. ${state.detail}`;
      stateBox.hidden = false;
      return;
    }
    stateBox.className = "note";
    stateBox.textContent = `The 3D replay is being prepared. ${state.detail}`;
    stateBox.hidden = false;
    setTimeout(waitForRecording, POLL_MS);
  }
  if (viewer.hasAttribute("data-preparing")) waitForRecording();

  // the two checkboxes: both skeletons (the stored recording), or one alone (?layer=); at least one stays shown
  const boxes = [document.getElementById("show-filtered"), document.getElementById("show-raw")];
  const note = document.getElementById("layers-note");
  for (const box of boxes) {
    box.addEventListener("change", () => {
      const shown = boxes.filter((b) => b.checked).map((b) => b.value);
      if (!shown.length) { box.checked = true; note.textContent = "At least one skeleton stays shown."; return; }
      note.textContent = "";
      const recording = viewer.dataset.recording + (shown.length === 1 ? `?layer=${shown[0]}` : "");
      viewer.src = Coach.url(`/replay/viewer/?playbackPath=${encodeURIComponent(recording)}`);
      viewer.hidden = false;
    });
  }
})();
