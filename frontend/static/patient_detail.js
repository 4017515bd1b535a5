/* Therapist's view of one patient: suggestions to review, a note form, progress plots, paginated sessions. */
"use strict";
(() => {
  const { api, url, el, fmtDate, fmtDateTime, exercises, exerciseName, runningPlan, showError } = Coach;
  const pid = document.getElementById("main").dataset.patientId;
  const PAGE = 10;
  let offset = 0;
  let lib = {};

  // How each checked metric reads in a sentence, and how its numbers are written.
  const METRICS = {
    repetitions: { what: "the number of repetitions", fmt: (x) => `${Math.round(x)}`, than: (t) => `the ${t} prescribed` },
    rom_deg: { what: "the range of motion", fmt: (x) => `${Math.round(x)}°`, than: (t) => `${t} (85% of the median of the weeks before)` },
    tempo_s_per_rep: { what: "the time per repetition", fmt: (x) => `${x.toFixed(1)} s` },
    "quality.tracked_fraction": { what: "the share of time the camera saw the patient", fmt: (x) => `${Math.round(x * 100)}%` },
    "quality.outlier_fraction": { what: "the share of implausible joint positions", fmt: (x) => `${Math.round(x * 100)}%` },
    active_days_last_7d: { what: "the number of days with this exercise in the last 7", fmt: (x) => `${Math.round(x)}`,
      than: (t) => `the ${t} the plan asks for` },
  };
  const COMPARED = { "<": "below", ">": "above", "==": "equal to" };

  /** Returns why a system suggestion was made, in words: "Because the range of motion (42°) was below 60°." */
  function ruleText(s) {
    if (s.source !== "system") return null;
    const m = METRICS[s.metric];
    let why;
    if (s.metric === "quality.ok") why = "Because the analysis judged this recording unreliable.";
    else if (!m || s.value === null || s.value === undefined || s.threshold === null) why = "Because one of the session's measurements was outside its expected range.";
    else {
      const thr = m.fmt(s.threshold);
      why = `Because ${m.what} (${m.fmt(s.value)}) was ${COMPARED[s.comparison] || s.comparison} ${m.than ? m.than(thr) : thr}.`;
    }
    return el("span", { class: "why" }, why);
  }

  function meta(s) {
    return el("div", { class: "small muted" }, ruleText(s), " ",
      s.session_id ? el("a", { href: url(`/therapist/sessions/${s.session_id}`) }, "see the session") : null,
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

  const FONT = 15;  // chart labels on therapist pages, px (at least 14)
  const POOR = "poor data quality";

  /** Returns one progress chart (Plotly, zoom and hover) of a metric over a patient's sessions, with its table. */
  function progressChart(title, mine, metric, { color, unit, yTitle, target, digits = 0, rangemode = "normal" }) {
    const value = (p) => (p[metric] === null || p[metric] === undefined ? null : +p[metric].toFixed(digits));
    const poor = (p) => p.quality_ok === false;
    const label = (p) => `${value(p) === null ? "—" : value(p) + unit} on ${fmtDateTime(p.started_at)}, session #${p.session_id}`
      + (poor(p) ? ` (${POOR})` : "");
    const traces = [{
      type: "scatter", mode: "lines+markers", name: yTitle, x: mine.map((p) => p.started_at), y: mine.map(value),
      line: { color, width: 2.5 }, connectgaps: true,
      marker: { color, size: 11, symbol: mine.map((p) => (poor(p) ? "circle-open" : "circle")), line: { color, width: 2.5 } },
      text: mine.map(label), hovertemplate: "%{text}<extra></extra>",
    }];
    if (mine.some(poor)) {  // the hollow marker, explained in the legend
      traces.push({ type: "scatter", mode: "markers", name: `○ ${POOR}`, x: [null], y: [null], hoverinfo: "skip",
        marker: { color, size: 11, symbol: "circle-open", line: { color, width: 2.5 } } });
    }
    const shapes = [], columns = ["Date", `${yTitle}${unit ? ` (${unit})` : ""}`];
    if (target) {
      shapes.push({ type: "line", xref: "paper", x0: 0, x1: 1, y0: target.y, y1: target.y, showlegend: true, name: target.label,
        line: { color: "#1b7f3b", width: 3, dash: "dash" } });
      columns.push("Prescribed");
    }
    columns.push("Data quality");
    const rows = mine.map((p) => [fmtDateTime(p.started_at), value(p), ...(target ? [target.y] : []), poor(p) ? "poor" : "good"]);
    return Plots.figure({
      title, traces, fontSize: FONT, height: 340,
      layout: { shapes, showlegend: true, hovermode: "closest",
        xaxis: { type: "date", tickformat: "%-d %b" },
        yaxis: { title: { text: yTitle + (unit ? ` (${unit})` : "") }, rangemode } },
      table: { caption: `${title} — one row per session`, columns, rows },
    });
  }

  function progressBlock(points, plan) {
    const box = document.getElementById("progress");
    box.replaceChildren();
    if (!points.length) { box.append(el("p", { class: "muted" }, "No sessions yet.")); return; }
    const slugs = [...new Set(points.map((p) => p.exercise_slug))];
    for (const slug of slugs) {
      const item = plan && plan.items.find((i) => i.exercise_slug === slug);
      const mine = points.filter((p) => p.exercise_slug === slug).sort((a, b) => new Date(a.started_at) - new Date(b.started_at));
      const name = exerciseName(lib, slug);
      box.append(progressChart(`${name}: repetitions vs prescribed`, mine, "repetitions", { color: Plots.COLORS[0], unit: "",
        yTitle: "repetitions", rangemode: "tozero", target: item ? { y: item.repetitions, label: `prescribed ${item.sets} × ${item.repetitions}` } : null }));
      const ex = lib[slug];
      box.append(progressChart(`${name}: range of motion` + (ex ? ` (normal ${ex.normal_range_min_deg}–${ex.normal_range_max_deg}°)` : ""),
        mine, "rom_deg", { color: Plots.COLORS[4], unit: "°", yTitle: "range of motion", digits: 1 }));
    }
  }

  async function loadSessions() {
    const body = document.querySelector("#sessions tbody");
    try {
      const page = await api(`/sessions?patient_id=${pid}&limit=${PAGE}&offset=${offset}`);
      body.replaceChildren(...page.items.map((s) => el("tr", { "data-session-id": s.id },
        el("td", {}, el("a", { href: url(`/therapist/sessions/${s.id}`), class: "session-link" }, fmtDateTime(s.started_at))),
        el("td", {}, exerciseName(lib, s.exercise_slug)),
        el("td", {}, s.repetitions === null ? "—" : s.repetitions),
        el("td", {}, s.rom_deg === null ? "—" : `${s.rom_deg.toFixed(1)}°`),
        el("td", {}, s.status !== "processed" ? el("span", { class: "flag", title: s.error || "" }, "analysis failed")
          : s.quality_ok === false ? el("span", { class: "flag" }, "⚠ poor") : "good"),
        el("td", {}, `${Math.round(s.duration_s)} s`),
        el("td", {}, el("a", { href: url(`/therapist/sessions/${s.id}/replay`) }, "3D replay")))));
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
