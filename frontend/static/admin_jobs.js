/* Re-analysis and jobs (admins): start a re-analysis of every patient's or one patient's sessions, follow the
   batches and their jobs (polled every 2 s while any job is queued or running), failures said in words. */
"use strict";
(() => {
  const { api, url, el, fmtDateTime, kindMessage } = Coach;
  const $ = (id) => document.getElementById(id);
  const POLL_BUSY_MS = 2000, POLL_IDLE_MS = 15000;
  const STATE_WORDS = { queued: "waiting", running: "running", done: "done", failed: "failed" };
  let shown = null;  // the batch whose jobs the lower table shows (null: the newest jobs of any batch)
  let patients = new Map();
  let timer = null;

  function batchState(b) {
    if (b.queued + b.running > 0) return b.running ? "Running" : `Waiting: ${b.queued} queued for a worker or a retry`;
    if (b.total === 0) return "Nothing to do";
    return b.failed ? `Finished, ${b.failed} failed` : "Finished";
  }

  function scopeText(b) {
    if (b.patient_id === null) return "every patient";
    const p = patients.get(b.patient_id);
    return p ? (p.full_name || p.email) : `patient ${b.patient_id}`;
  }

  function progressCell(b) {
    const finished = b.done + b.failed;
    const bar = el("progress", { max: String(Math.max(b.total, 1)), value: String(finished),
      "aria-label": `${finished} of ${b.total} sessions finished` });
    return el("td", {}, bar, ` ${finished} / ${b.total}`);
  }

  function batchRow(b) {
    const show = el("button", { type: "button", class: "btn btn-quiet", "data-batch": b.batch,
      "aria-pressed": String(shown === b.batch) }, "Show jobs");
    show.addEventListener("click", () => { shown = b.batch; refresh(); });
    return el("tr", { "data-batch": b.batch },
      el("td", {}, fmtDateTime(b.created_at)), el("td", {}, scopeText(b)), progressCell(b),
      el("td", { class: b.failed ? "bad" : "" }, batchState(b)), el("td", {}, b.queued_by || "command line"),
      el("td", {}, show));
  }

  function jobRow(j) {
    const session = j.session_id === null ? "—"
      : el("a", { href: url(`/therapist/sessions/${j.session_id}`) }, `Session ${j.session_id}`);
    let what = j.error || "";
    if (j.status === "done") what = j.changed ? "New metrics stored; the old ones are kept." : "Already analysed with this version: nothing changed.";
    else if (j.status === "queued" && j.error) what = `Will try again: ${j.error}`;
    else if (j.status === "queued") what = "Waiting for a worker.";
    else if (j.status === "running") what = "A worker is analysing it.";
    return el("tr", { "data-job": String(j.id), "data-status": j.status },
      el("td", {}, String(j.id)), el("td", {}, session),
      el("td", { class: j.status === "failed" ? "bad" : "" }, STATE_WORDS[j.status] || j.status),
      el("td", {}, `${j.attempts} of ${j.max_attempts}`), el("td", {}, what));
  }

  function fill(table, rows, empty, cols) {
    $(table).querySelector("tbody").replaceChildren(...(rows.length ? rows
      : [el("tr", {}, el("td", { colspan: String(cols), class: "muted" }, empty))]));
  }

  async function refresh() {
    clearTimeout(timer);
    let busy = false;
    try {
      const overview = await api("/reanalysis");
      $("version").textContent = overview.analysis_version;
      fill("batches", overview.batches.map(batchRow), "No re-analysis has been started yet.", 6);
      busy = overview.batches.some((b) => b.queued + b.running > 0);
      const query = shown ? `?batch=${encodeURIComponent(shown)}&limit=200` : "?limit=50";
      const jobs = await api(`/jobs${query}`);
      $("jobs-of").textContent = shown ? "of the chosen re-analysis" : "(newest first)";
      fill("jobs", jobs.map(jobRow), "No jobs.", 5);
      $("live").textContent = busy ? "Updating every 2 seconds while work is waiting or running."
        : `Up to date at ${new Date().toLocaleTimeString()}.`;
      $("live").className = "small muted";
    } catch (err) {
      $("live").textContent = `Could not update: ${kindMessage(err)} Trying again in a few seconds.`;
      $("live").className = "small alert";
      busy = true;
    }
    timer = setTimeout(refresh, busy ? POLL_BUSY_MS : POLL_IDLE_MS);
  }

  async function loadPatients() {
    try {
      const page = await api("/patients?limit=200");
      patients = new Map(page.items.map((p) => [p.id, p]));
      $("scope").append(...page.items.map((p) => el("option", { value: String(p.id) }, `${p.full_name || p.email}'s sessions`)));
    } catch (err) { $("start-msg").textContent = `The patient list could not be loaded: ${kindMessage(err)}`; }
  }

  $("start").addEventListener("submit", async (e) => {
    e.preventDefault();
    const btn = $("start-btn"), msg = $("start-msg");
    btn.disabled = true;
    const pid = $("scope").value;
    try {
      const out = await api("/reanalysis", { method: "POST", body: pid ? { patient_id: Number(pid) } : {} });
      msg.className = "small";
      msg.textContent = out.total ? `${out.total} session(s) queued for analysis version ${out.analysis_version}.`
        : `Nothing to do: every stored session of ${pid ? "this patient" : "every patient"} is already analysed with version ${out.analysis_version} or queued.`;
      shown = out.total ? out.batch : shown;
      refresh();
    } catch (err) {
      msg.className = "small alert";
      msg.textContent = `Nothing was queued: ${kindMessage(err)}`;
    } finally { btn.disabled = false; }
  });

  loadPatients().then(refresh);
})();
