/* Therapist's view of one patient: the plan (edit, new, history), suggestions to review, a note form, the patient's
   replies to advice, progress plots, paginated sessions. */
"use strict";
(() => {
  const { api, url, el, fmtDate, fmtDateTime, exercises, exerciseName, runningPlan, showError } = Coach;
  const pid = document.getElementById("main").dataset.patientId;
  const PAGE = 10;
  let offset = 0;
  let lib = {};
  let patientLocale = null;  // the language the patient reads (GET /patients/{id}: locale; null: their browser's)

  /** Returns a language's name in its own language ("Deutsch"), as the language select lists it. */
  function languageName(code) {
    const option = [...document.querySelectorAll("#patient-locale option")].find((o) => o.value === code);
    return option ? option.textContent : code;
  }

  /** Says which language the patient reads, that the system's advice is written for each reader, and that free text
   *  (advice, the plan's title, note and hints) reaches the patient as typed, not translated. */
  function showLanguage(locale) {
    patientLocale = locale || null;
    const name = patientLocale ? languageName(patientLocale) : null;
    const reads = document.getElementById("patient-reads-language");
    reads.textContent = name || I18n.t("the language of their browser");
    if (patientLocale) reads.setAttribute("lang", patientLocale); else reads.removeAttribute("lang");
    document.getElementById("patient-reads-how").textContent = patientLocale
      ? I18n.t("(their pages, the exercise instructions and the system's advice)")
      : I18n.t("(not chosen: their pages follow the language their browser asks for)");
    document.getElementById("patient-reads").hidden = false;
    const pending = document.getElementById("pending-language");
    pending.textContent = I18n.t("The system's suggestions are written for each reader: you see them in {mine}, the patient reads them in {theirs}.",
      { mine: languageName(I18n.locale), theirs: name || I18n.t("the language of their browser") });
    pending.hidden = false;
    const notes = {
      "suggestion-free-text": name
        ? I18n.t("Not translated: the patient reads {language}, and sees your advice exactly as you type it.", { language: name })
        : I18n.t("Not translated: the patient sees your advice exactly as you type it."),
      "plan-free-text": name
        ? I18n.t("Not translated: the patient reads {language}, and sees the plan's title, note and hints exactly as you type them.", { language: name })
        : I18n.t("Not translated: the patient sees the plan's title, note and hints exactly as you type them."),
    };
    for (const [id, text] of Object.entries(notes)) {
      const p = document.getElementById(id);
      p.textContent = text;
      p.hidden = false;
    }
  }

  /** Returns, for a system suggestion shown here in another language than the patient's, the language they read. */
  function shownIn(s) {
    if (s.source !== "system" || !s.locale || !patientLocale || s.locale === patientLocale) return null;
    return el("span", { class: "shown-in" }, " · ", I18n.t("the patient reads it in {language}", { language: languageName(patientLocale) }));
  }

  // How each checked metric reads in a sentence, and how its numbers are written (in the page's language).
  const METRICS = {
    repetitions: { what: I18n.t("the number of repetitions"), fmt: (x) => I18n.number(x),
      than: (t) => I18n.t("the {count} prescribed", { count: t }) },
    rom_deg: { what: I18n.t("the range of motion"), fmt: (x) => `${I18n.number(x)}°`,
      than: (t) => I18n.t("{angle} (85% of the median of the weeks before)", { angle: t }) },
    tempo_s_per_rep: { what: I18n.t("the time per repetition"), fmt: (x) => I18n.t("{seconds} s", { seconds: I18n.number(x, 1) }) },
    "quality.tracked_fraction": { what: I18n.t("the share of time the camera saw the patient"), fmt: (x) => I18n.percent(x) },
    "quality.outlier_fraction": { what: I18n.t("the share of implausible joint positions"), fmt: (x) => I18n.percent(x) },
    active_days_last_7d: { what: I18n.t("the number of days with this exercise in the last 7"), fmt: (x) => I18n.number(x),
      than: (t) => I18n.t("the {count} the plan asks for", { count: t }) },
    pain_nrs: { what: I18n.t("the pain the patient said after the set"), fmt: (x) => I18n.t("{pain} of 10", { pain: I18n.number(x) }),
      than: (t) => I18n.t("their pain alert level ({level})", { level: t }) },
    pain_nrs_median_7d: { what: I18n.t("the median pain said after sets in the last 7 days"),
      fmt: (x) => I18n.t("{pain} of 10", { pain: I18n.number(x, 1) }),
      than: (t) => I18n.t("{level} (2 points above the median of the 4 weeks before)", { level: t }) },
  };
  const COMPARED = { "<": I18n.t("below"), ">": I18n.t("above"), ">=": I18n.t("at or above"), "==": I18n.t("equal to") };

  /** Returns why a system suggestion was made, in words: "Because the range of motion (42°) was below 60°." */
  function ruleText(s) {
    if (s.source !== "system") return null;
    const m = METRICS[s.metric];
    let why;
    if (s.metric === "quality.ok") why = I18n.t("Because the analysis judged this recording unreliable.");
    else if (!m || s.value === null || s.value === undefined || s.threshold === null) why = I18n.t("Because one of the session's measurements was outside its expected range.");
    else {
      const thr = m.fmt(s.threshold);
      why = I18n.t("Because {what} ({value}) was {compared} {limit}.", { what: m.what, value: m.fmt(s.value),
        compared: COMPARED[s.comparison] || s.comparison, limit: m.than ? m.than(thr) : thr });
    }
    return el("span", { class: "why" }, why);
  }

  /** Returns the suggestion's why, a link to its session named by the session's date, and when it was written. */
  function meta(s) {
    const session = s.session_id ? el("a", { href: url(`/therapist/sessions/${s.session_id}`), class: "session-link" },
      s.session_started_at ? I18n.t("session of {when}", { when: fmtDateTime(s.session_started_at) }) : I18n.t("see the session")) : null;
    return el("div", { class: "small muted" }, ruleText(s), " ", session, session ? " · " : "",
      I18n.t("written {when}", { when: fmtDateTime(s.created_at) }), shownIn(s));
  }

  async function decide(s, action, li) {
    li.querySelectorAll("button").forEach((b) => (b.disabled = true));
    try {
      await api(`/suggestions/${s.id}/${action}`, { method: "POST" });
      li.replaceChildren(el("p", { class: "note" }, action === "approve" ? I18n.t("Approved — the patient can see it now.") : I18n.t("Dismissed — the patient will not see it.")),
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
      if (!page.items.length) list.append(el("li", { class: "muted" }, I18n.t("Nothing to review.")));
      for (const s of page.items) {
        const li = el("li", { "data-suggestion-id": s.id }, el("p", {}, s.text), meta(s));
        li.append(el("div", { class: "actions" },
          el("button", { class: "btn btn-good", type: "button", onclick: () => decide(s, "approve", li) }, I18n.t("Approve")),
          el("button", { class: "btn btn-bad", type: "button", onclick: () => decide(s, "dismiss", li) }, I18n.t("Dismiss"))));
        list.append(li);
      }
    } catch (err) { showError(err); }
  }

  const DECIDED_PAGE = 5;
  const DECIDED = { approved: I18n.t("Approved"), dismissed: I18n.t("Dismissed"), superseded: I18n.t("Replaced by newer advice") };
  let decidedOffset = 0;
  /** Shows one page of the sent and decided suggestions, newest first, with Newer/Older buttons. */
  async function loadDecided() {
    const list = document.getElementById("decided");
    const page = await api(`/patients/${pid}/suggestions?decided=true&limit=${DECIDED_PAGE}&offset=${decidedOffset}`);
    if (!page.items.length && decidedOffset > 0) { decidedOffset = Math.max(0, decidedOffset - DECIDED_PAGE); return loadDecided(); }
    list.replaceChildren(...page.items.map((s) => el("li", {},
      el("strong", {}, s.source === "therapist" ? I18n.t("You wrote") : DECIDED[s.status]), ": ", s.text, meta(s))));
    if (!page.items.length) list.append(el("li", { class: "muted" }, I18n.t("None yet.")));
    const pages = Math.max(1, Math.ceil(page.total / DECIDED_PAGE));
    document.getElementById("decided-info").textContent = I18n.t("page {page} of {pages} ({total} in all)",
      { page: Math.floor(decidedOffset / DECIDED_PAGE) + 1, pages, total: page.total });
    document.getElementById("decided-prev").disabled = decidedOffset === 0;
    document.getElementById("decided-next").disabled = decidedOffset + DECIDED_PAGE >= page.total;
    document.getElementById("decided-pager").hidden = page.total <= DECIDED_PAGE;
  }
  document.getElementById("decided-prev").addEventListener("click", () => { decidedOffset = Math.max(0, decidedOffset - DECIDED_PAGE); loadDecided().catch(showError); });
  document.getElementById("decided-next").addEventListener("click", () => { decidedOffset += DECIDED_PAGE; loadDecided().catch(showError); });

  const REPLIES_PAGE = 20;
  const newHere = new Set();  // replies that were unread when this page first showed them: marked "new" while it is open
  /** Shows the patient's replies to advice, newest first, and marks the unread ones read (the therapist has seen them). */
  async function loadReplies() {
    const page = await api(`/patients/${pid}/replies?limit=${REPLIES_PAGE}`);
    const unread = page.items.filter((r) => !r.read_at).map((r) => r.id);
    unread.forEach((id) => newHere.add(id));
    const list = document.getElementById("replies");
    list.replaceChildren(...page.items.map((r) => RepliesView.item(r, { isNew: newHere.has(r.id) })));
    if (!page.items.length) list.append(el("li", { class: "muted" }, I18n.t("No replies yet.")));
    const more = document.getElementById("replies-more");
    more.hidden = page.total <= page.items.length;
    more.textContent = I18n.t("The newest {shown} of {total} replies are shown.", { shown: page.items.length, total: page.total });
    if (unread.length) await api(`/patients/${pid}/replies/read`, { method: "POST", body: { reply_ids: unread } });
  }

  const FONT = 15;  // chart labels on therapist pages, px (at least 14)
  const POOR = I18n.t("poor data quality");

  /** Returns one progress chart (Plotly, zoom and hover) of a metric over a patient's sessions, with its table. */
  function progressChart(title, mine, metric, { color, unit, yTitle, target, digits = 0, rangemode = "normal" }) {
    const value = (p) => (p[metric] === null || p[metric] === undefined ? null : +p[metric].toFixed(digits));
    const poor = (p) => p.quality_ok === false;
    const label = (p) => I18n.t("{value} on {when}, session #{id}", { value: value(p) === null ? "—" : I18n.number(value(p), digits) + unit,
      when: fmtDateTime(p.started_at), id: String(p.session_id) }) + (poor(p) ? ` (${POOR})` : "");
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
    const shapes = [], columns = [I18n.t("Date"), `${yTitle}${unit ? ` (${unit})` : ""}`];
    if (target) {
      shapes.push({ type: "line", xref: "paper", x0: 0, x1: 1, y0: target.y, y1: target.y, showlegend: true, name: target.label,
        line: { color: "#1b7f3b", width: 3, dash: "dash" } });
      columns.push(I18n.t("Prescribed"));
    }
    columns.push(I18n.t("Data quality"));
    const rows = mine.map((p) => [fmtDateTime(p.started_at), value(p) === null ? null : I18n.number(value(p), digits),
      ...(target ? [target.y] : []), poor(p) ? I18n.t("poor") : I18n.t("good")]);
    return Plots.figure({
      title, traces, fontSize: FONT, height: 340,
      layout: { shapes, showlegend: true, hovermode: "closest",
        xaxis: Plots.dateAxis(mine.map((p) => p.started_at)),
        yaxis: { title: { text: yTitle + (unit ? ` (${unit})` : "") }, rangemode } },
      table: { caption: I18n.t("{title} — one row per session", { title }), columns, rows },
    });
  }

  function progressBlock(points, plan) {
    const box = document.getElementById("progress");
    box.replaceChildren();
    if (!points.length) { box.append(el("p", { class: "muted" }, I18n.t("No sessions yet."))); return; }
    const slugs = [...new Set(points.map((p) => p.exercise_slug))];
    for (const slug of slugs) {
      const item = plan && plan.items.find((i) => i.exercise_slug === slug);
      const mine = points.filter((p) => p.exercise_slug === slug).sort((a, b) => new Date(a.started_at) - new Date(b.started_at));
      const name = exerciseName(lib, slug);
      box.append(progressChart(I18n.t("{exercise}: repetitions vs prescribed", { exercise: name }), mine, "repetitions",
        { color: Plots.COLORS[0], unit: "", yTitle: I18n.t("repetitions"), rangemode: "tozero",
          target: item ? { y: item.repetitions, label: I18n.t("prescribed {sets} × {reps}", { sets: item.sets, reps: item.repetitions }) } : null }));
      const ex = lib[slug];
      box.append(progressChart(ex ? I18n.t("{exercise}: range of motion (normal {low}–{high}°)", { exercise: name,
        low: I18n.number(ex.normal_range_min_deg), high: I18n.number(ex.normal_range_max_deg) })
        : I18n.t("{exercise}: range of motion", { exercise: name }),
        mine, "rom_deg", { color: Plots.COLORS[4], unit: "°", yTitle: I18n.t("range of motion"), digits: 1 }));
      if (ex && ex.mdc95_rom_deg !== null && ex.mdc95_rom_deg !== undefined) {
        box.append(el("p", { class: "muted small" }, I18n.t("A change in range of motion under {angle}° between two sessions is "
          + "within what the measurement and the movement vary by (minimal detectable change, 95 %).", { angle: I18n.number(ex.mdc95_rom_deg) })));
      }
    }
  }

  /** Adds the chart of pain (0-10 NRS) and effort (Borg CR10) the patient said after each set, all exercises, with
   *  the patient's pain alert level as a dashed line; nothing when the patient has never answered. */
  function feelingChart(points, alertAbove) {
    const said = points.filter((p) => p.pain_nrs !== null || p.effort_cr10 !== null)
      .sort((a, b) => new Date(a.started_at) - new Date(b.started_at));
    if (!said.length) return;
    const x = said.map((p) => p.started_at);
    const hover = (what, key) => said.map((p) => I18n.t("{what} {answer} after {exercise} on {when}, session #{id}", { what,
      answer: p[key] === null ? I18n.t("not said") : I18n.t("{pain} of 10", { pain: p[key] }),
      exercise: exerciseName(lib, p.exercise_slug), when: fmtDateTime(p.started_at), id: String(p.session_id) }));
    const trace = (name, key, color, symbol) => ({ type: "scatter", mode: "lines+markers", name, x, y: said.map((p) => p[key]),
      connectgaps: true, line: { color, width: 2.5 }, marker: { color, size: 11, symbol }, text: hover(name, key),
      hovertemplate: "%{text}<extra></extra>" });
    const traces = [trace(I18n.t("pain (0–10, NRS)"), "pain_nrs", Plots.COLORS[1], "circle"),
      trace(I18n.t("effort (Borg CR10)"), "effort_cr10", Plots.COLORS[3], "square")];
    const shapes = [{ type: "line", xref: "paper", x0: 0, x1: 1, y0: alertAbove, y1: alertAbove, showlegend: true,
      name: I18n.t("pain alert above {level}", { level: alertAbove }), line: { color: Plots.COLORS[1], width: 2, dash: "dash" } }];
    document.getElementById("progress").prepend(Plots.figure({  // first: pain is what needs a therapist soonest
      title: I18n.t("How the sets felt: pain and effort the patient said (all exercises)"), traces, fontSize: FONT, height: 340,
      layout: { shapes, showlegend: true, hovermode: "closest", xaxis: Plots.dateAxis(x),
        yaxis: { title: { text: I18n.t("of 10") }, range: [-0.3, 10.3], dtick: 2 } },
      table: { caption: I18n.t("Pain and effort after each set — one row per answered set"),
        columns: [I18n.t("Date"), I18n.t("Exercise"), I18n.t("Pain (0–10)"), I18n.t("Effort (Borg CR10)")],
        rows: said.map((p) => [fmtDateTime(p.started_at), exerciseName(lib, p.exercise_slug), p.pain_nrs, p.effort_cr10]) },
    }));
  }

  async function loadSessions() {
    const body = document.querySelector("#sessions tbody");
    try {
      const page = await api(`/sessions?patient_id=${pid}&limit=${PAGE}&offset=${offset}`);
      body.replaceChildren(...page.items.map((s) => el("tr", { "data-session-id": s.id },
        el("td", {}, el("a", { href: url(`/therapist/sessions/${s.id}`), class: "session-link" }, fmtDateTime(s.started_at))),
        el("td", {}, exerciseName(lib, s.exercise_slug)),
        el("td", {}, s.repetitions === null ? "—" : s.repetitions),
        el("td", {}, s.rom_deg === null ? "—" : `${I18n.number(s.rom_deg, 1)}°`),
        el("td", {}, s.status !== "processed" ? el("span", { class: "flag", title: s.error || "" }, I18n.t("analysis failed"))
          : s.quality_ok === false ? el("span", { class: "flag" }, I18n.t("⚠ poor")) : I18n.t("good")),
        el("td", {}, I18n.t("{seconds} s", { seconds: I18n.number(s.duration_s) })),
        el("td", {}, el("a", { href: url(`/therapist/sessions/${s.id}/replay`) }, I18n.t("3D replay"))))));
      if (!page.items.length) body.append(el("tr", {}, el("td", { colspan: 7, class: "muted" }, I18n.t("No sessions yet."))));
      const last = Math.min(page.total, offset + page.items.length);
      document.getElementById("page-info").textContent = page.total
        ? I18n.t("{first}–{last} of {total}", { first: offset + 1, last, total: page.total }) : "";
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
    if (!text) { msg.textContent = I18n.t("Please write the advice first."); msg.className = "alert"; msg.hidden = false; return; }
    try {
      await api(`/patients/${pid}/suggestions`, { method: "POST", body: { text } });
      box.value = "";
      msg.textContent = I18n.t("Sent — the patient can see it now."); msg.className = "note"; msg.hidden = false;
      loadDecided();
    } catch (err) { msg.textContent = Coach.kindMessage(err); msg.className = "alert"; msg.hidden = false; }
  });

  // ---- Plan: the running plan, a form to edit it or write a new one, past plans ----
  const NUMBERS = {  // field -> label, limits (client checks; the API checks the same)
    sets: { label: I18n.t("Sets"), min: 1, max: 100 },
    repetitions: { label: I18n.t("Repetitions"), min: 1, max: 1000 },
    frequency_per_week: { label: I18n.t("Days per week"), min: 1, max: 7 },
    target_rom_deg: { label: I18n.t("Target range (°)"), min: 1, max: 180, optional: true },  // of motion, optional
  };
  let plans = [], running = null, editing = null;  // editing: the plan being edited (null: a new plan)
  let patientZone = null;  // the patient's IANA time zone (null: the clinic's)
  let rowSeq = 0;

  const isoDay = (d) => d.toISOString().slice(0, 10);
  const addDays = (iso, n) => { const d = new Date(iso + "T00:00:00Z"); d.setUTCDate(d.getUTCDate() + n); return isoDay(d); };
  const dayText = (iso) => fmtDate(iso + "T12:00:00Z", { day: "numeric", month: "short", year: "numeric" });
  const span = (p) => `${dayText(p.start_date)} – ${p.end_date ? dayText(p.end_date) : I18n.t("open end")}`;
  const itemText = (i) => I18n.nt("{exercise}: {sets} × {reps}, {n} day a week", "{exercise}: {sets} × {reps}, {n} days a week",
    i.frequency_per_week, { exercise: exerciseName(lib, i.exercise_slug), sets: i.sets, reps: i.repetitions })
    + (i.target_rom_deg ? I18n.t(", target {angle}°", { angle: I18n.number(i.target_rom_deg) }) : "");

  /** Returns the time zone the reminder times are read in: the patient's, else the clinic's. */
  function zoneText() { return patientZone || I18n.t("the clinic's time zone"); }

  function renderPlan() {
    const box = document.getElementById("plan-current");
    box.replaceChildren();
    document.getElementById("plan-edit").hidden = !running;
    if (!running) box.append(el("p", {}, I18n.t("No plan is running. Write a new plan below.")));
    else {
      box.append(el("p", { class: "lead", id: "plan-title-shown" }, el("strong", {}, running.title), ` · ${span(running)}`),
        el("p", { class: "small muted" }, I18n.t("Prescribed by {name}", { name: running.therapist_name || I18n.t("an administrator") })),
        el("ul", { class: "plan-items", id: "plan-items" }, running.items.map((i) => el("li", {}, itemText(i),
          i.notes ? el("span", { class: "muted" }, ` — ${i.notes}`) : null))),
        el("p", { id: "plan-reminders-shown" }, running.reminder_times.length
          ? I18n.t("Reminders: {times} ({zone})", { times: running.reminder_times.join(", "), zone: zoneText() })
          : I18n.t("No reminder times.")),
        running.notes ? el("p", { id: "plan-note-shown" }, el("strong", {}, I18n.t("Note to the patient:")), " ", running.notes)
          : el("p", { class: "muted" }, I18n.t("No note to the patient.")));
      if (!running.items.length) box.querySelector("ul").append(el("li", { class: "muted" }, I18n.t("No exercises.")));
    }
    const past = plans.filter((p) => p !== running);
    const list = document.getElementById("plan-history");
    list.replaceChildren(...past.map((p) => el("li", { "data-plan-id": p.id },
      el("div", {}, el("strong", {}, p.title), ` · ${span(p)}`),
      el("div", { class: "small muted" }, I18n.t("Prescribed by {name}", { name: p.therapist_name || I18n.t("an administrator") })
        + " · " + (p.items.map(itemText).join("; ") || I18n.t("no exercises"))))));
    if (!past.length) list.append(el("li", { class: "muted" }, I18n.t("No earlier plans.")));
  }

  /** Returns the box that shows a field's error: the element "<field id>-err" (null for a field without one). */
  function errorBox(input) { return document.getElementById(`${input.id}-err`); }

  /** Shows msg next to a field (or hides it when msg is empty); a field without an error box only gets marked. */
  function fieldError(input, errBox, msg) {
    if (errBox) {
      errBox.textContent = msg || "";
      errBox.hidden = !msg;
    }
    if (input) { if (msg) input.setAttribute("aria-invalid", "true"); else input.removeAttribute("aria-invalid"); }
  }

  function numberField(row, name, value) {
    const spec = NUMBERS[name], id = `plan-row${row.dataset.row}-${name}`;
    const input = el("input", { id, name, type: "number", inputmode: "numeric", min: spec.min, max: spec.max,
      step: name === "target_rom_deg" ? "any" : 1, value: value ?? "", "aria-describedby": `${id}-err` });
    return el("div", { class: "field" }, el("label", { for: id }, spec.label), input,
      el("p", { class: "field-error", id: `${id}-err`, hidden: true }));
  }

  function renumber() {
    document.querySelectorAll("#plan-rows .plan-row").forEach((row, n) => {
      row.querySelector("legend").textContent = I18n.t("Exercise {number}", { number: n + 1 });
      row.querySelector(".plan-remove").setAttribute("aria-label", I18n.t("Remove exercise {number}", { number: n + 1 }));
    });
  }

  function addRow(item) {
    const row = el("fieldset", { class: "plan-row", "data-row": ++rowSeq });
    const id = `plan-row${rowSeq}`;
    const select = el("select", { id: `${id}-exercise`, name: "exercise_slug", "aria-describedby": `${id}-exercise-err` },
      el("option", { value: "" }, I18n.t("Choose an exercise…")),
      Object.values(lib).sort((a, b) => a.name.localeCompare(b.name)).map((e) => el("option", { value: e.slug }, e.name)));
    select.value = item ? item.exercise_slug : "";
    row.append(el("legend", {}, I18n.t("Exercise")),
      el("div", { class: "field field-wide" }, el("label", { for: select.id }, I18n.t("Exercise")), select,
        el("p", { class: "field-error", id: `${id}-exercise-err`, hidden: true })),
      numberField(row, "sets", item ? item.sets : 2),
      numberField(row, "repetitions", item ? item.repetitions : 10),
      numberField(row, "frequency_per_week", item ? item.frequency_per_week : 3),
      numberField(row, "target_rom_deg", item && item.target_rom_deg ? Math.round(item.target_rom_deg * 10) / 10 : ""),
      el("div", { class: "field field-wide" }, el("label", { for: `${id}-notes` }, I18n.t("Hint for this exercise (optional)")),
        el("input", { id: `${id}-notes`, name: "notes", maxlength: 2000, value: item ? item.notes : "",
          "aria-describedby": "plan-free-text" })),
      el("button", { class: "btn btn-bad plan-remove", type: "button", onclick: () => { row.remove(); renumber(); } }, I18n.t("Remove")));
    document.getElementById("plan-rows").append(row);
    renumber();
    return row;
  }

  function openForm(plan) {
    editing = plan;
    const form = document.getElementById("plan-form");
    const today = isoDay(new Date());
    document.getElementById("plan-form-h").textContent = plan ? I18n.t("Edit the running plan") : I18n.t("New plan (replaces the running one from its first day)");
    document.getElementById("plan-title").value = plan ? plan.title : (running ? running.title : I18n.t("Home programme"));
    document.getElementById("plan-start").value = plan ? plan.start_date : today;
    document.getElementById("plan-end").value = plan ? plan.end_date || "" : addDays(today, 27);
    document.getElementById("plan-notes").value = plan ? plan.notes : running ? running.notes : "";
    document.getElementById("plan-reminders").value = (plan ? plan.reminder_times : running ? running.reminder_times : []).join(", ");
    document.getElementById("plan-rows").replaceChildren();
    const items = plan ? plan.items : running ? running.items : [];
    items.forEach(addRow);
    if (!items.length) addRow(null);
    form.querySelectorAll(".field-error").forEach((p) => fieldError(null, p, ""));
    form.querySelectorAll("[aria-invalid]").forEach((i) => i.removeAttribute("aria-invalid"));
    document.getElementById("plan-msg").hidden = true;
    document.getElementById("plan-saved").hidden = true;
    form.hidden = false;
    document.getElementById("plan-title").focus();
  }

  /** Returns the plan body of the form, or null after showing each problem next to its field. */
  function readForm() {
    let ok = true;
    const fail = (input, msg) => { fieldError(input, errorBox(input), msg); ok = false; };
    const clear = (input) => fieldError(input, errorBox(input), "");
    const title = document.getElementById("plan-title"), start = document.getElementById("plan-start");
    const end = document.getElementById("plan-end"), notes = document.getElementById("plan-notes");
    const reminders = document.getElementById("plan-reminders");
    [title, start, end, notes, reminders].forEach(clear);
    const reminderTimes = reminders.value.split(/[,;\s]+/).filter(Boolean)
      .map((t) => (/^\d:\d\d$/.test(t) ? "0" + t : t));  // 9:00 -> 09:00
    const badTime = reminderTimes.find((t) => !/^([01]\d|2[0-3]):[0-5]\d$/.test(t));
    if (badTime) fail(reminders, I18n.t("“{time}” is not a time like 09:00 (hours 00 to 23, minutes 00 to 59, separated by commas).", { time: badTime }));
    if (!title.value.trim()) fail(title, I18n.t("Please give the plan a title."));
    if (!start.value) fail(start, I18n.t("Please choose the plan's first day."));
    if (end.value && start.value && end.value < start.value) fail(end, I18n.t("The last day must not be before the first day."));
    const items = [];
    const rows = [...document.querySelectorAll("#plan-rows .plan-row")];
    fieldError(null, document.getElementById("plan-rows-err"), rows.length ? "" : I18n.t("Please add at least one exercise."));
    if (!rows.length) ok = false;
    const chosen = new Map();  // exercise slug -> its row's number: each exercise once in a plan
    for (const [k, row] of rows.entries()) {
      const select = row.querySelector("select");
      clear(select);
      if (!select.value) fail(select, I18n.t("Please choose an exercise."));
      else if (chosen.has(select.value)) fail(select, I18n.t("{exercise} is already exercise {number} of this plan. Give each exercise once; change its sets there instead.",
        { exercise: exerciseName(lib, select.value), number: chosen.get(select.value) }));
      else chosen.set(select.value, k + 1);
      const item = { exercise_slug: select.value, notes: row.querySelector('input[name="notes"]').value.trim() };
      for (const [name, spec] of Object.entries(NUMBERS)) {
        const input = row.querySelector(`input[name="${name}"]`);
        clear(input);
        const raw = input.value.trim();
        if (!raw) {
          if (spec.optional) { item[name] = null; continue; }
          fail(input, I18n.t("Please enter the {field} (a number from {min} to {max}).", { field: spec.label.toLowerCase(), min: spec.min, max: spec.max }));
          continue;
        }
        const x = Number(raw);
        const whole = name !== "target_rom_deg";
        if (!Number.isFinite(x) || (whole && !Number.isInteger(x)) || input.validity.badInput) fail(input, whole ? I18n.t("Please enter a whole number.") : I18n.t("Please enter a number."));
        else if (x < spec.min || x > spec.max) fail(input, I18n.t("{field} must be between {min} and {max}.", { field: spec.label, min: spec.min, max: spec.max }));
        else item[name] = x;
      }
      items.push(item);
    }
    if (!ok) return null;
    return { title: title.value.trim(), notes: notes.value.trim(), start_date: start.value, end_date: end.value || null, items,
      reminder_times: reminderTimes };
  }

  /** Places each part of the API's 422 detail ("body.items.1.repetitions: Input should be ...") next to its field. */
  function showApiErrors(err) {
    const msg = document.getElementById("plan-msg");
    msg.textContent = Coach.kindMessage(err);
    msg.hidden = false;
    if (err.status !== 422 || !err.detail) return;
    const rows = [...document.querySelectorAll("#plan-rows .plan-row")];
    for (const part of String(err.detail).split("; ")) {
      const m = part.match(/^body\.(?:items\.(\d+)\.)?(\w+): (.*)$/);
      if (!m) continue;
      const scope = m[1] === undefined ? document.getElementById("plan-form") : rows[+m[1]];
      const input = scope && scope.querySelector(`[name="${m[2]}"]`);
      const label = input && scope.querySelector(`label[for="${input.id}"]`);
      if (input) fieldError(input, errorBox(input),
        `${label ? label.textContent : m[2]}: ${m[3]}.`);
    }
  }

  async function savePlan(ev) {
    ev.preventDefault();
    document.getElementById("plan-msg").hidden = true;
    const body = readForm();
    if (!body) {
      const first = document.querySelector('#plan-form [aria-invalid="true"]');
      if (first) first.focus();
      return;
    }
    const button = document.getElementById("plan-save");
    button.disabled = true;
    try {
      if (editing) await api(`/plans/${editing.id}`, { method: "PUT", body });
      else {
        await api(`/patients/${pid}/plans`, { method: "POST", body });
        if (running && running.start_date < body.start_date) {  // the running plan ends the day before the new one
          const old = { title: running.title, notes: running.notes, start_date: running.start_date, end_date: addDays(body.start_date, -1),
            reminder_times: running.reminder_times,
            items: running.items.map((i) => ({ exercise_slug: i.exercise_slug, sets: i.sets, repetitions: i.repetitions,
              frequency_per_week: i.frequency_per_week, target_rom_deg: i.target_rom_deg, notes: i.notes })) };
          await api(`/plans/${running.id}`, { method: "PUT", body: old });
        }
      }
      document.getElementById("plan-form").hidden = true;
      await loadPlans();
      const saved = document.getElementById("plan-saved");
      saved.textContent = editing ? I18n.t("Plan saved — the patient sees it now.") : I18n.t("New plan saved — the patient sees it now.");
      saved.hidden = false;
      overview().catch(showError);
    } catch (err) {
      showApiErrors(err);
    } finally { button.disabled = false; }
  }

  async function loadPlans() {
    plans = (await api(`/patients/${pid}/plans?limit=50`)).items;
    running = runningPlan(plans);
    renderPlan();
    return running;
  }

  document.getElementById("patient-locale").addEventListener("change", async (ev) => {
    const said = document.getElementById("patient-locale-saved");
    try {
      const out = await api(`/patients/${pid}`, { method: "PATCH", body: { locale: ev.target.value || null } });
      said.textContent = out.locale ? I18n.t("Saved: the patient's pages and new advice are in this language now.") : I18n.t("Saved: the patient's browser decides.");
      showLanguage(out.locale);
      loadPending();
      loadDecided().catch(showError);
    } catch (err) { said.textContent = ""; showError(err); }
  });
  const tzInput = document.getElementById("patient-tz");
  document.getElementById("patient-tz-list").replaceChildren(
    ...(Intl.supportedValuesOf ? Intl.supportedValuesOf("timeZone") : []).map((z) => el("option", { value: z })));
  tzInput.addEventListener("change", async () => {
    const said = document.getElementById("patient-tz-saved");
    try {
      const out = await api(`/patients/${pid}`, { method: "PATCH", body: { time_zone: tzInput.value.trim() || null } });
      patientZone = out.time_zone;
      said.textContent = out.time_zone ? I18n.t("Saved: reminders follow {zone}.", { zone: out.time_zone }) : I18n.t("Saved: reminders follow the clinic's time zone.");
      renderPlan();
    } catch (err) { said.textContent = err.status === 422 ? I18n.t("Not saved: {reason}", { reason: err.detail }) : ""; if (err.status !== 422) showError(err); }
  });
  document.getElementById("pain-alert").addEventListener("submit", async (ev) => {
    ev.preventDefault();
    const input = document.getElementById("pain-alert-above"), said = document.getElementById("pain-alert-msg");
    const text = input.value.trim(), value = Number(text);
    if (!/^\d$/.test(text)) {  // a whole number 0-9: pain above 9 of 10 can only be 10
      input.setAttribute("aria-invalid", "true");
      said.textContent = I18n.t("Enter a whole number from 0 to 9.");
      input.focus();
      return;
    }
    input.removeAttribute("aria-invalid");
    try {
      const out = await api(`/patients/${pid}`, { method: "PATCH", body: { pain_alert_above: value } });
      input.value = out.pain_alert_above;
      said.textContent = I18n.t("Saved: pain above {level} of 10 now raises the patient's attention score.", { level: out.pain_alert_above });
      await overview();  // the pain chart's alert line moves to the new level
    } catch (err) { said.textContent = ""; showError(err); }
  });
  document.getElementById("plan-edit").addEventListener("click", () => openForm(running));
  document.getElementById("plan-new").addEventListener("click", () => openForm(null));
  document.getElementById("plan-add").addEventListener("click", () => addRow(null).querySelector("select").focus());
  document.getElementById("plan-cancel").addEventListener("click", () => { document.getElementById("plan-form").hidden = true; });
  document.getElementById("plan-form").addEventListener("submit", savePlan);

  /** Shows the patient's name, the summary line and the progress charts (against the running plan). */
  async function overview() {
    const [patient, summary, progress] = await Promise.all([
      api(`/patients/${pid}`), api(`/patients/${pid}/summary`), api(`/patients/${pid}/progress`),
    ]);
    document.getElementById("patient-name").textContent = patient.full_name || patient.email;
    document.getElementById("patient-locale").value = patient.locale || "";
    showLanguage(patient.locale);
    document.getElementById("patient-tz").value = patient.time_zone || "";
    if (patientZone !== patient.time_zone) { patientZone = patient.time_zone; renderPlan(); }
    const alertInput = document.getElementById("pain-alert-above");
    if (document.activeElement !== alertInput) alertInput.value = patient.pain_alert_above;
    document.title = `${patient.full_name || patient.email} · Kinect Home Coach`;
    const plan = running;
    const parts = [patient.email];
    parts.push(summary.last_session ? I18n.t("last session {day}", { day: fmtDate(summary.last_session.started_at) }) : I18n.t("no session yet"));
    parts.push(summary.planned_this_week
      ? I18n.t("this week {done} of {planned} sessions", { done: summary.sessions_this_week, planned: summary.planned_this_week })
      : I18n.nt("this week {n} session", "this week {n} sessions", summary.sessions_this_week));
    if (plan) parts.push(I18n.t("plan “{title}”:", { title: plan.title }) + " " + plan.items.map((i) => I18n.t("{exercise} {sets}×{reps}, {days}/week",
      { exercise: exerciseName(lib, i.exercise_slug), sets: i.sets, reps: i.repetitions, days: i.frequency_per_week })).join("; "));
    document.getElementById("patient-summary").textContent = parts.join(" · ");
    progressBlock(progress.points, plan);
    feelingChart(progress.points, patient.pain_alert_above);
  }

  async function load() {
    try {
      lib = await exercises();
      await loadPlans();
      await overview();
    } catch (err) { showError(err); }
    loadPending();
    loadDecided().catch(showError);
    loadReplies().catch(showError);
    loadSessions();
  }
  load();
  Coach.onChange(pid, load);  // new sessions, suggestions, replies and plan changes show without reloading the page
})();
