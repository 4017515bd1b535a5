/* Therapist's view of one patient: suggestions to review, a note form, progress plots, paginated sessions. */
"use strict";
(() => {
  const { api, el, fmtDate, fmtDateTime, exercises, exerciseName, runningPlan, showError } = Coach;
  const pid = document.getElementById("main").dataset.patientId;
  const PAGE = 10;
  let offset = 0;
  let lib = {};

  function ruleText(s) {
    if (s.source !== "system") return null;
    const thr = s.threshold === null ? "" : ` ${+s.threshold.toFixed(2)}`;
    const val = s.value === null || s.value === undefined ? "" : ` ${+s.value.toFixed(2)}`;
    return el("span", { class: "rule", title: "the rule that fired: metric value comparison threshold" }, `${s.rule}: ${s.metric}${val} ${s.comparison}${thr}`);
  }

  function meta(s) {
    return el("div", { class: "small muted" }, ruleText(s), " ",
      s.session_id ? el("a", { href: `/therapist/sessions/${s.session_id}/replay` }, `session #${s.session_id}`) : null,
      ` · ${fmtDateTime(s.created_at)}`);
  }

  async function decide(s, action, li) {
    li.querySelectorAll("button").forEach((b) => (b.disabled = true));
    try {
      await api(`/suggestions/${s.id}/${action}`, { method: "POST" });
      li.replaceChildren(el("p", { class: "note" }, action === "approve" ? "Approved — the patient can see it now." : "Dismissed — the patient will not see it."),
        el("p", { class: "small muted" }, s.text));
      li.classList.add("decided");
      loadDecided();
    } catch (err) {
      li.querySelectorAll("button").forEach((b) => (b.disabled = false));
      showError(err);
    }
  }

  async function loadPending() {
    const list = document.getElementById("pending");
    try {
      const page = await api(`/patients/${pid}/suggestions?status=pending&limit=50`);
      list.replaceChildren();
      if (!page.items.length) list.append(el("li", { class: "muted" }, "Nothing to review."));
      for (const s of page.items) {
        const li = el("li", { "data-suggestion-id": s.id }, el("p", {}, s.text), meta(s));
        li.append(el("div", { class: "actions" },
          el("button", { class: "btn btn-good", type: "button", onclick: () => decide(s, "approve", li) }, "Approve"),
          el("button", { class: "btn btn-bad", type: "button", onclick: () => decide(s, "dismiss", li) }, "Dismiss")));
        list.append(li);
      }
    } catch (err) { showError(err); }
  }

  async function loadDecided() {
    const list = document.getElementById("decided");
    const page = await api(`/patients/${pid}/suggestions?limit=30`);
    const done = page.items.filter((s) => s.status !== "pending").slice(0, 8);
    list.replaceChildren(...done.map((s) => el("li", {},
      el("strong", {}, s.source === "therapist" ? "You wrote" : { approved: "Approved", dismissed: "Dismissed", superseded: "Replaced by newer advice" }[s.status]), ": ", s.text, meta(s))));
    if (!done.length) list.append(el("li", { class: "muted" }, "None yet."));
  }

  function progressBlock(points, plan) {
    const box = document.getElementById("progress");
    box.replaceChildren();
    if (!points.length) { box.append(el("p", { class: "muted" }, "No sessions yet.")); return; }
    const slugs = [...new Set(points.map((p) => p.exercise_slug))];
    for (const slug of slugs) {
      const item = plan && plan.items.find((i) => i.exercise_slug === slug);
      const mine = points.filter((p) => p.exercise_slug === slug);
      const name = exerciseName(lib, slug);
      const mark = (p, y, unit) => ({ t: p.started_at, y, hollow: p.quality_ok === false,
        label: `${y}${unit} on ${fmtDateTime(p.started_at)} (session #${p.session_id}${p.quality_ok === false ? ", poor data quality" : ""})` });
      box.append(Chart.timeChart([{ name: "repetitions", points: mine.map((p) => mark(p, p.repetitions, "")) }], {
        title: `${name}: repetitions vs prescribed`, yMin: 0, yLabel: "reps",
        target: item ? { y: item.repetitions, label: `prescribed ${item.sets} × ${item.repetitions}` } : null, hollowNote: "poor data quality" }));
      const ex = lib[slug];
      box.append(Chart.timeChart([{ name: "range of motion", points: mine.map((p) => mark(p, p.rom_deg === null ? null : Math.round(p.rom_deg * 10) / 10, "°")), color: "#6a3d9a" }], {
        title: `${name}: range of motion (°)` + (ex ? `, normal ${ex.normal_range_min_deg}–${ex.normal_range_max_deg}°` : ""), yLabel: "degrees", hollowNote: "poor data quality" }));
    }
  }

  async function loadSessions() {
    const body = document.querySelector("#sessions tbody");
    try {
      const page = await api(`/sessions?patient_id=${pid}&limit=${PAGE}&offset=${offset}`);
      body.replaceChildren(...page.items.map((s) => el("tr", { "data-session-id": s.id },
        el("td", {}, fmtDateTime(s.started_at)),
        el("td", {}, exerciseName(lib, s.exercise_slug)),
        el("td", {}, s.repetitions === null ? "—" : s.repetitions),
        el("td", {}, s.rom_deg === null ? "—" : `${s.rom_deg.toFixed(1)}°`),
        el("td", {}, s.status !== "processed" ? el("span", { class: "flag", title: s.error || "" }, "analysis failed")
          : s.quality_ok === false ? el("span", { class: "flag" }, "⚠ poor") : "good"),
        el("td", {}, `${Math.round(s.duration_s)} s`),
        el("td", {}, el("a", { href: `/therapist/sessions/${s.id}/replay` }, "3D replay")))));
      if (!page.items.length) body.append(el("tr", {}, el("td", { colspan: 7, class: "muted" }, "No sessions yet.")));
      const last = Math.min(page.total, offset + page.items.length);
      document.getElementById("page-info").textContent = page.total ? `${offset + 1}–${last} of ${page.total}` : "";
      document.getElementById("prev").disabled = offset === 0;
      document.getElementById("next").disabled = last >= page.total;
    } catch (err) { showError(err); }
  }

  document.getElementById("prev").addEventListener("click", () => { offset = Math.max(0, offset - PAGE); loadSessions(); });
  document.getElementById("next").addEventListener("click", () => { offset += PAGE; loadSessions(); });

  document.getElementById("suggestion-form").addEventListener("submit", async (ev) => {
    ev.preventDefault();
    const box = document.getElementById("suggestion-text"), msg = document.getElementById("suggestion-msg");
    const text = box.value.trim();
    msg.hidden = true;
    if (!text) { msg.textContent = "Please write the advice first."; msg.className = "alert"; msg.hidden = false; return; }
    try {
      await api(`/patients/${pid}/suggestions`, { method: "POST", body: { text } });
      box.value = "";
      msg.textContent = "Sent — the patient can see it now."; msg.className = "note"; msg.hidden = false;
      loadDecided();
    } catch (err) { msg.textContent = Coach.kindMessage(err); msg.className = "alert"; msg.hidden = false; }
  });

  async function load() {
    try {
      lib = await exercises();
      const [patient, summary, plans, progress] = await Promise.all([
        api(`/patients/${pid}`), api(`/patients/${pid}/summary`), api(`/patients/${pid}/plans?limit=20`), api(`/patients/${pid}/progress`),
      ]);
      document.getElementById("patient-name").textContent = patient.full_name || patient.email;
      document.title = `${patient.full_name || patient.email} · Kinect Home Coach`;
      const plan = runningPlan(plans.items);
      const parts = [patient.email];
      parts.push(summary.last_session ? `last session ${fmtDate(summary.last_session.started_at)}` : "no session yet");
      parts.push(summary.planned_this_week ? `this week ${summary.sessions_this_week} of ${summary.planned_this_week} sessions` : `this week ${summary.sessions_this_week} sessions`);
      if (plan) parts.push(`plan “${plan.title}”: ` + plan.items.map((i) => `${exerciseName(lib, i.exercise_slug)} ${i.sets}×${i.repetitions}, ${i.frequency_per_week}/week`).join("; "));
      document.getElementById("patient-summary").textContent = parts.join(" · ");
      progressBlock(progress.points, plan);
    } catch (err) { showError(err); }
    loadPending();
    loadDecided().catch(showError);
    loadSessions();
  }
  load();
})();
