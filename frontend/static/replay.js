/* Replay page: session facts from the API, then the 3D viewer (a viser server started on demand) in an iframe. */
"use strict";
(() => {
  const { api, exercises, exerciseName, fmtDateTime, showError, ApiError, toLogin } = Coach;
  const sid = document.getElementById("main").dataset.sessionId;
  const info = document.getElementById("replay-info");

  async function viewer() {
    const resp = await fetch(`/therapist/sessions/${sid}/replay/viewer`, { credentials: "same-origin", headers: { Accept: "application/json" } });
    if (resp.status === 401) { toLogin(); throw new ApiError(401, "NotAuthenticated", "Please sign in again."); }
    const data = await resp.json().catch(() => null);
    if (!resp.ok) throw new ApiError(resp.status, (data && data.error) || "HTTPError", (data && data.detail) || resp.statusText);
    return data;
  }

  async function load() {
    try {
      const [lib, s] = await Promise.all([exercises(), api(`/sessions/${sid}`)]);
      document.getElementById("back").href = `/therapist/patients/${s.patient_id}`;
      document.getElementById("back").textContent = "← Back to the patient";
      const name = exerciseName(lib, s.exercise_slug);
      document.getElementById("replay-title").textContent = `${name} · ${fmtDateTime(s.started_at)}`;
      const facts = [`${s.repetitions === null ? "—" : s.repetitions} repetitions`,
        s.rom_deg === null ? null : `range of motion ${s.rom_deg.toFixed(1)}°`,
        s.quality_ok === false ? "⚠ poor data quality" : null, `${s.n_frames} frames, ${s.duration_s.toFixed(1)} s`].filter(Boolean);
      info.textContent = facts.join(" · ") + " — starting the 3D viewer…";
      const v = await viewer();
      const frame = document.getElementById("viewer");
      frame.src = v.url;
      frame.hidden = false;
      info.textContent = facts.join(" · ") + ". Use Play and the Frame slider on the right; drag to turn the view.";
    } catch (err) { info.textContent = ""; showError(err); }
  }
  load();
})();
