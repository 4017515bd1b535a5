/* Re-analysis and jobs (admins): start a re-analysis of every patient's or one patient's sessions, follow the
   batches and their jobs (polled every 2 s while any job is queued or running), failures said in words. */
"use strict";
(() => {
  const { api, url, el, fmtDateTime, kindMessage } = Coach;
  const $ = (id) => document.getElementById(id);
  const POLL_BUSY_MS = 2000, POLL_IDLE_MS = 15000;
  const STATE_WORDS = { queued: I18n.t("waiting"), running: I18n.t("running"), done: I18n.t("done"), failed: I18n.t("failed") };
  // what a finished job of the other kinds did (the list shows every kind; only a re-analysis compares metrics)
  const DONE_WORDS = { replay: I18n.t("3D replay built."), detail: I18n.t("Session details built."),
    export: I18n.t("Export built."), archive: I18n.t("The patient's archive was made."), camera_end: I18n.t("Camera set finished.") };
  let shown = null;  // the batch whose jobs the lower table shows (null: the newest jobs of any batch)
  let patients = new Map();
  let timer = null;

  function batchState(b) {
    if (b.queued + b.running > 0) return b.running ? I18n.t("Running") : I18n.t("Waiting: {count} queued for a worker or a retry", { count: b.queued });
    if (b.total === 0) return I18n.t("Nothing to do");
    return b.failed ? I18n.t("Finished, {count} failed", { count: b.failed }) : I18n.t("Finished");
  }

  function scopeText(b) {
    if (b.patient_id === null) return I18n.t("every patient");
    const p = patients.get(b.patient_id);
    return p ? (p.full_name || p.email) : I18n.t("patient {id}", { id: b.patient_id });
  }

  function progressCell(b) {
    const finished = b.done + b.failed;
    const bar = el("progress", { max: String(Math.max(b.total, 1)), value: String(finished),
      "aria-label": I18n.t("{finished} of {total} sessions finished", { finished, total: b.total }) });
    return el("td", {}, bar, ` ${finished} / ${b.total}`);
  }

  function batchRow(b) {
    const show = el("button", { type: "button", class: "btn btn-quiet", "data-batch": b.batch,
      "aria-pressed": String(shown === b.batch) }, I18n.t("Show jobs"));
    show.addEventListener("click", () => { shown = b.batch; refresh(); });
    return el("tr", { "data-batch": b.batch },
      el("td", {}, fmtDateTime(b.created_at)), el("td", {}, scopeText(b)), progressCell(b),
      el("td", { class: b.failed ? "bad" : "" }, batchState(b)), el("td", {}, b.queued_by || I18n.t("command line")),
      el("td", {}, show));
  }

  function jobRow(j) {
    const session = j.session_id === null ? "—"
      : el("a", { href: url(`/therapist/sessions/${j.session_id}`) }, I18n.t("Session {id}", { id: String(j.session_id) }));
    let what = j.error || "";
    if (j.status === "done" && j.kind !== "reanalyze") what = DONE_WORDS[j.kind] || "";
    else if (j.status === "done") what = j.changed ? I18n.t("New metrics stored; the old ones are kept.") : I18n.t("Already analysed with this version: nothing changed.");
    else if (j.status === "queued" && j.error) what = I18n.t("Will try again: {reason}", { reason: j.error });
    else if (j.status === "queued") what = I18n.t("Waiting for a worker.");
    else if (j.status === "running") what = I18n.t("A worker is analysing it.");
    return el("tr", { "data-job": String(j.id), "data-status": j.status },
      el("td", {}, String(j.id)), el("td", {}, session),
      el("td", { class: j.status === "failed" ? "bad" : "" }, STATE_WORDS[j.status] || j.status),
      el("td", {}, I18n.t("{count} of {total}", { count: j.attempts, total: j.max_attempts })), el("td", {}, what));
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
      fill("batches", overview.batches.map(batchRow), I18n.t("No re-analysis has been started yet."), 6);
      busy = overview.batches.some((b) => b.queued + b.running > 0);
      const query = shown ? `?batch=${encodeURIComponent(shown)}&limit=200` : "?limit=50";
      const jobs = await api(`/jobs${query}`);
      $("jobs-of").textContent = shown ? I18n.t("of the chosen re-analysis") : I18n.t("(newest first)");
      fill("jobs", jobs.map(jobRow), I18n.t("No jobs."), 5);
      $("live").textContent = busy ? I18n.t("Updating every 2 seconds while work is waiting or running.")
        : I18n.t("Up to date at {time}.", { time: new Date().toLocaleTimeString(I18n.tag) });
      $("live").className = "small muted";
    } catch (err) {
      $("live").textContent = I18n.t("Could not update: {reason} Trying again in a few seconds.", { reason: kindMessage(err) });
      $("live").className = "small alert";
      busy = true;
    }
    timer = setTimeout(refresh, busy ? POLL_BUSY_MS : POLL_IDLE_MS);
  }

  async function loadPatients() {
    try {
      const page = await api("/patients?limit=200");
      patients = new Map(page.items.map((p) => [p.id, p]));
      $("scope").append(...page.items.map((p) => el("option", { value: String(p.id) }, I18n.t("{name}'s sessions", { name: p.full_name || p.email }))));
    } catch (err) { $("start-msg").textContent = I18n.t("The patient list could not be loaded: {reason}", { reason: kindMessage(err) }); }
  }

  $("start").addEventListener("submit", async (e) => {
    e.preventDefault();
    const btn = $("start-btn"), msg = $("start-msg");
    btn.disabled = true;
    const pid = $("scope").value;
    try {
      const out = await api("/reanalysis", { method: "POST", body: pid ? { patient_id: Number(pid) } : {} });
      msg.className = "small";
      msg.textContent = out.total
        ? I18n.nt("{n} session queued for analysis version {version}.", "{n} sessions queued for analysis version {version}.", out.total, { version: out.analysis_version })
        : pid ? I18n.t("Nothing to do: every stored session of this patient is already analysed with version {version} or queued.", { version: out.analysis_version })
          : I18n.t("Nothing to do: every stored session of every patient is already analysed with version {version} or queued.", { version: out.analysis_version });
      shown = out.total ? out.batch : shown;
      refresh();
    } catch (err) {
      msg.className = "small alert";
      msg.textContent = I18n.t("Nothing was queued: {reason}", { reason: kindMessage(err) });
    } finally { btn.disabled = false; }
  });

  loadPatients().then(refresh);
})();
