/* Patient feedback screen: greeting, this week's plan, the last session in plain words, advice and the patient's
 * replies to it, a progress chart. */
"use strict";
(() => {
  const { api, el, plainDay, median, exercises, exerciseName, runningPlan, showError, startOfWeekUTC, DAY } = Coach;
  const main = document.getElementById("main");
  const pid = main.dataset.patientId;
  const firstName = main.dataset.name;

  function greeting() {
    const h = new Date().getHours();
    const name = firstName;
    const named = h < 12 ? I18n.t("Good morning, {name}!", { name }) : h < 18 ? I18n.t("Good afternoon, {name}!", { name })
      : I18n.t("Good evening, {name}!", { name });
    const plain = h < 12 ? I18n.t("Good morning!") : h < 18 ? I18n.t("Good afternoon!") : I18n.t("Good evening!");
    document.getElementById("greeting").textContent = firstName ? named : plain;
  }

  /** Returns what the patient counts: in English "sit-to-stands", "mini squats"; in the other languages the
   *  exercise's (translated) name, which their sentences place as a label. */
  function plural(lib, slug) {
    if (I18n.locale !== "en") return exerciseName(lib, slug);
    const name = exerciseName(lib, slug).toLowerCase();
    if (name === "sit to stand") return "sit-to-stands";  // i18n: not shown (English pages only); the same words as the advice (backend/suggestions/rules.py)
    return name.endsWith("s") ? name : name + "s";
  }

  function lastSessionBlock(last, item, lib, history) {
    const box = document.getElementById("last-session");
    box.replaceChildren();
    if (!last) { box.append(el("p", { class: "lead" }, I18n.t("No exercise recorded yet. When you do your exercises in front of the camera, you will see them here."))); return; }
    const what = plural(lib, last.exercise_slug);
    const when = plainDay(last.started_at);
    let sentence;
    if (last.status !== "processed" || last.repetitions === null) {
      sentence = I18n.t("We could not count your {what} {when}. Please make sure the camera can see all of you next time.", { what, when });
    } else if (item && last.repetitions >= item.repetitions) {
      sentence = I18n.t("You did all {goal} {what} {when} — well done!", { goal: item.repetitions, what, when });
    } else if (item && last.repetitions >= 0.7 * item.repetitions) {
      sentence = I18n.t("You did {done} of {goal} {what} {when} — well done!", { done: last.repetitions, goal: item.repetitions, what, when });
    } else if (item) {
      sentence = I18n.t("You did {done} of {goal} {what} {when}. Good effort — next time, try for a few more.", { done: last.repetitions, goal: item.repetitions, what, when });
    } else {
      sentence = I18n.t("You did {done} {what} {when} — well done!", { done: last.repetitions, what, when });
    }
    box.append(el("p", { class: "big-sentence", id: "last-sentence" }, sentence));
    if (last.rom_deg !== null && last.rom_deg !== undefined) {
      const rom = Math.round(last.rom_deg);
      const since = new Date(last.started_at) - 28 * DAY;
      const before = median(history.filter((p) => p.session_id !== last.id && new Date(p.started_at) < new Date(last.started_at)
        && +new Date(p.started_at) >= since && p.quality_ok !== false).map((p) => p.rom_deg));
      let words = I18n.t("You moved through {rom} degrees.", { rom });
      if (before !== null) {
        const b = Math.round(before), ratio = last.rom_deg / before;
        if (ratio >= 1.05) words += " " + I18n.t("That is more than in the last weeks (about {before} degrees). Very good!", { before: b });
        else if (ratio > 0.95) words += " " + I18n.t("That is about the same as in the last weeks ({before} degrees). Keep it up.", { before: b });
        else words += " " + I18n.t("In the last weeks it was about {before} degrees. That is fine — move gently, only as far as is comfortable.", { before: b });
      }
      box.append(el("p", { class: "lead", id: "rom-sentence" }, words));
    }
    if (last.quality_ok === false) box.append(el("p", { class: "muted" }, I18n.t("The camera did not see you well this time, so these numbers may be a little off.")));
    box.append(el("div", { id: "last-feeling" }));
    lastFeeling();
  }

  let askAbout = null;  // the newest set of today that nobody asked about yet: {id, client} (its session ids)
  /** Asks how the newest set of today felt under "Your last exercise", unless the live panel asks about it: a set
   *  the home computer or the camera page recorded without the live panel, or one whose panel was closed. */
  function lastFeeling() {
    const box = document.getElementById("last-feeling");
    if (!box) return;
    const live = Live.current;
    const inPanel = live && ((live.result && live.result.id === askAbout?.id) || (live.session_id && live.session_id === askAbout?.client));
    box.replaceChildren(...(askAbout && !inPanel ? [Feeling.block(askAbout.id)].filter(Boolean) : []));
  }
  Feeling.listen(lastFeeling);
  window.addEventListener("coach-live-closed", () => {
    if (askAbout && Feeling.said(askAbout.id)) askAbout = null;  // answered in the live panel: not asked again
    lastFeeling();
  });

  /** Returns the newest session when it is of today and how it felt is not answered (nor skipped) yet, else null. */
  async function notAsked(last) {
    if (!last || new Date(last.started_at).toDateString() !== new Date().toDateString()) return null;
    const said = await api(`/sessions/${last.id}/feeling`).catch(() => ({ answered_at: "unknown" }));  // not asked then
    return said.answered_at ? null : { id: last.id, client: last.client_session_id };
  }

  /** Returns today's sets of one exercise against the plan, one line each: "set 1 of 2: 6 of 10". */
  function todaySets(item, todaySessions) {
    const lines = [];
    const n = Math.max(item.sets, todaySessions.length);
    for (let k = 0; k < n; k++) {
      const s = todaySessions[k];
      const counted = s && s.repetitions !== null && s.repetitions !== undefined;
      const done = s && !counted ? I18n.t("not counted") : I18n.t("{done} of {goal}", { done: s ? s.repetitions : 0, goal: item.repetitions });
      const full = s && s.repetitions >= item.repetitions;
      lines.push(k < item.sets ? I18n.t("set {set} of {sets}: {done}", { set: k + 1, sets: item.sets, done }) + (full ? " ✓" : "")
        : I18n.t("extra set: {done}", { done: counted ? s.repetitions : I18n.t("not counted") }));
    }
    return lines;
  }

  /** The big Start of one exercise (shown while the home computer is connected: Live.render). */
  function startButton(lib, item, doneToday) {
    const next = doneToday + 1;
    const label = next <= item.sets ? I18n.t("set {set} of {sets}", { set: next, sets: item.sets }) : I18n.t("extra set");
    const name = exerciseName(lib, item.exercise_slug);
    return el("button", { class: "btn btn-big btn-good start", type: "button", hidden: true,
      "aria-label": I18n.t("Start {exercise}, {set}", { exercise: name, set: label }), onclick: () => Live.start(item, label) }, I18n.t("Start"));
  }

  function planBlock(plan, lib, weekSessions) {
    const list = document.getElementById("plan");
    const note = document.getElementById("plan-note");
    list.replaceChildren();
    note.hidden = !(plan && plan.notes);
    note.replaceChildren(...(plan && plan.notes ? [el("strong", {}, I18n.t("From your therapist:") + " "), plan.notes] : []));
    if (!plan || !plan.items.length) { list.append(el("li", {}, I18n.t("You have no exercises planned right now. Your therapist will add them."))); return; }
    const today = new Date().toDateString();
    for (const item of plan.items) {
      const mine = weekSessions.filter((s) => s.exercise_slug === item.exercise_slug);
      const mineToday = mine.filter((s) => new Date(s.started_at).toDateString() === today)
        .sort((a, b) => new Date(a.started_at) - new Date(b.started_at));  // each stored session is one set
      const doneToday = mineToday.length > 0;
      const weekDone = mine.length >= item.frequency_per_week;
      const perWeek = item.frequency_per_week;
      let status = I18n.t("Done {done} of {goal} times this week", { done: mine.length, goal: perWeek });
      if (weekDone) status = I18n.t("All done this week ({done} of {goal})", { done: mine.length, goal: perWeek }) + " ✓";
      if (doneToday) status += " · " + I18n.t("done today");
      const sets = I18n.nt("{n} set of {reps}", "{n} sets of {reps}", item.sets, { reps: item.repetitions });
      const often = I18n.nt("once a week", "{n} times a week", perWeek);
      const how = item.target_rom_deg ? I18n.t("{sets}, {often}, moving through about {rom} degrees", { sets, often, rom: Math.round(item.target_rom_deg) })
        : I18n.t("{sets}, {often}", { sets, often });
      list.append(el("li", { "data-exercise": item.exercise_slug },
        el("span", { class: "week-badge", "aria-hidden": "true" },  // "done N times this week" (the status line says it in words)
          el("span", { class: "tick" + (weekDone ? " done" : "") }, weekDone ? "✓" : I18n.t("{n}×", { n: mine.length })),
          el("span", { class: "week-label" }, I18n.t("this week"))),
        el("div", {},
          el("div", { class: "what" }, exerciseName(lib, item.exercise_slug)),
          el("div", { class: "how" }, how),
          el("div", {}, status),
          el("div", { class: "today" }, el("strong", {}, I18n.t("Today:")), todaySets(item, mineToday).map((t) => el("span", {}, t))),
          Demo.block(item, lib[item.exercise_slug], exerciseName(lib, item.exercise_slug))),
        el("div", { class: "starts" }, startButton(lib, item, mineToday.length),
          CameraEntry.link(item, exerciseName(lib, item.exercise_slug), mineToday.length + 1 <= item.sets
            ? I18n.t("set {set} of {sets}", { set: mineToday.length + 1, sets: item.sets }) : I18n.t("extra set")))));
    }
    CameraEntry.reveal().then((yes) => { if (yes) Live.render(); });  // the home computer's line names the camera
  }

  /** Today's next reminder of the plan, at its time in the patient's time zone (the server's reckoning). */
  function reminderBlock(reminders) {
    const box = document.getElementById("reminder");
    const next = reminders.next;
    box.hidden = !next;
    if (!next) { box.textContent = ""; return; }
    const time = new Date(next.due_at).toLocaleTimeString(I18n.tag, { hour: "2-digit", minute: "2-digit", timeZone: reminders.time_zone });
    box.textContent = I18n.t("Reminder: your exercises at {time}", { time });
  }

  let advice = [], replies = [];
  /** Shows the advice the patient sees, each with their answers and the reply buttons; keeps the text box being
   *  typed in focused when the page redraws it (a reply or new data arrived). */
  function adviceBlock() {
    const list = document.getElementById("advice");
    const focused = document.activeElement && list.contains(document.activeElement) ? document.activeElement : null;
    const where = focused && focused.id ? [focused.id, focused.selectionStart, focused.selectionEnd] : null;
    list.replaceChildren();
    const shown = advice.filter((s) => s.status === "approved" || s.source === "therapist");
    if (!shown.length) { list.append(el("li", {}, I18n.t("No new advice. Keep going with your exercises!"))); return; }
    for (const s of shown.slice(0, 5)) {
      const mine = replies.filter((r) => r.suggestion_id === s.id).reverse();  // oldest first
      list.append(el("li", { "data-suggestion-id": s.id }, el("span", { class: "from" }, (s.source === "therapist" ? I18n.t("From your therapist") : I18n.t("Tip, checked by your therapist"))
        + " · " + Coach.fmtDate(s.created_at, { day: "numeric", month: "long" })), el("p", { class: "advice-text" }, s.text),
        AdviceReply.block(pid, s, mine)));
    }
    const again = where && document.getElementById(where[0]);
    if (again) { again.focus(); if (again.setSelectionRange && where[1] !== undefined) again.setSelectionRange(where[1], where[2]); }
  }
  AdviceReply.onChange = adviceBlock;

  function chartBlock(plan, lib, points) {
    const box = document.getElementById("charts");
    box.replaceChildren();
    const slugs = plan && plan.items.length ? plan.items.map((i) => i.exercise_slug) : [...new Set(points.map((p) => p.exercise_slug))];
    const since = Date.now() - 42 * DAY;
    if (!points.length) { box.append(el("p", {}, I18n.t("Your progress will show here after your first exercises."))); return; }
    for (const slug of slugs) {
      const item = plan && plan.items.find((i) => i.exercise_slug === slug);
      const mine = points.filter((p) => p.exercise_slug === slug && +new Date(p.started_at) >= since && p.repetitions !== null)
        .sort((a, b) => new Date(a.started_at) - new Date(b.started_at));
      if (!mine.length) {
        box.append(el("h3", {}, exerciseName(lib, slug)), el("p", {}, I18n.t("No exercise in the last six weeks yet.")));
        continue;
      }
      const day = (p) => Coach.fmtDate(p.started_at, { day: "numeric", month: "long" });
      const color = Plots.COLORS[0];
      const traces = [{ type: "scatter", mode: "lines+markers", name: I18n.t("what you did"), x: mine.map((p) => p.started_at),
        y: mine.map((p) => p.repetitions), line: { color, width: 4 }, marker: { color, size: 14 },
        text: mine.map((p) => I18n.t("{done} on {day}", { done: p.repetitions, day: day(p) })), hovertemplate: "%{text}<extra></extra>" }];
      const shapes = item ? [{ type: "line", xref: "paper", x0: 0, x1: 1, y0: item.repetitions, y1: item.repetitions,
        showlegend: true, name: I18n.t("your goal: {goal}", { goal: item.repetitions }), line: { color: "#1b7f3b", width: 4, dash: "dash" } }] : [];
      const top = Math.max(item ? item.repetitions : 0, ...mine.map((p) => p.repetitions), 1);
      box.append(Plots.figure({
        title: I18n.t("{exercise}: how many each time", { exercise: exerciseName(lib, slug) }), traces, fontSize: 20, height: 320,
        config: { displayModeBar: false },
        layout: { shapes, showlegend: true, dragmode: false,
          xaxis: Plots.dateAxis(mine.map((p) => p.started_at), { fixedrange: true, nticks: window.innerWidth < 600 ? 3 : 5 }),
          yaxis: { fixedrange: true, range: [0, Math.ceil(top * 1.15)], nticks: 4 } },
        table: { caption: I18n.t("{exercise}: how many you did each time", { exercise: exerciseName(lib, slug) }),
          columns: [I18n.t("Day"), I18n.t("How many"), ...(item ? [I18n.t("Your goal")] : [])],
          rows: mine.map((p) => [day(p), p.repetitions, ...(item ? [item.repetitions] : [])]) },
      }));
    }
  }

  /** Returns a date axis whose day ticks are every other day on a phone, so the dates stay level and readable. */
  function narrowDays(axis) {
    return window.innerWidth < 600 && axis.dtick === DAY ? { ...axis, dtick: 2 * DAY, tickangle: 0 } : axis;
  }

  /** Adds the chart of the pain and effort the patient said after each exercise in the last six weeks (0-10 each);
   *  nothing when they have not answered. */
  function feelingChart(lib, points) {
    const since = Date.now() - 42 * DAY;
    const said = points.filter((p) => +new Date(p.started_at) >= since && (p.pain_nrs !== null || p.effort_cr10 !== null))
      .sort((a, b) => new Date(a.started_at) - new Date(b.started_at));
    if (!said.length) return;
    const day = (p) => Coach.fmtDate(p.started_at, { day: "numeric", month: "long" });
    const x = said.map((p) => p.started_at);
    const num = (v) => (v === null ? "—" : I18n.number(v, 1));
    const pain = I18n.t("Pain"), hard = I18n.t("How hard");
    const trace = (name, key, color, symbol, dash) => ({ type: "scatter", mode: "lines+markers", name, x, y: said.map((p) => p[key]),
      connectgaps: true, line: { color, width: 4, dash }, marker: { color, size: 14, symbol },
      text: said.map((p) => I18n.t("{what}: {value} of 10 after {exercise} on {day}",
        { what: name, value: num(p[key]), exercise: exerciseName(lib, p.exercise_slug), day: day(p) })),
      hovertemplate: "%{text}<extra></extra>" });
    document.getElementById("charts").append(Plots.figure({
      title: I18n.t("How it felt after your exercises (0 to 10)"), fontSize: 20, height: 320,
      traces: [trace(pain, "pain_nrs", Plots.COLORS[1], "circle", "solid"), trace(hard, "effort_cr10", Plots.COLORS[3], "square", "dot")],
      config: { displayModeBar: false },
      layout: { showlegend: true, dragmode: false,
        xaxis: narrowDays(Plots.dateAxis(x, { fixedrange: true, nticks: window.innerWidth < 600 ? 3 : 5 })),
        yaxis: { fixedrange: true, range: [-0.3, 10.3], dtick: 5 } },
      table: { caption: I18n.t("How it felt after each exercise"),
        columns: [I18n.t("Day"), I18n.t("Exercise"), I18n.t("Pain (0 to 10)"), I18n.t("How hard (0 to 10)")],
        rows: said.map((p) => [day(p), exerciseName(lib, p.exercise_slug), num(p.pain_nrs), num(p.effort_cr10)]) },
    }));
  }

  async function load() {
    greeting();
    const since = startOfWeekUTC().toISOString();
    try {
      const [lib, plans, latest, week, suggestions, progress, answers, reminders] = await Promise.all([
        exercises(),
        api(`/patients/${pid}/plans?limit=20`),
        api(`/sessions?patient_id=${pid}&limit=1`),
        api(`/sessions?patient_id=${pid}&since=${encodeURIComponent(since)}&limit=200`),
        api(`/patients/${pid}/suggestions?limit=10`),
        api(`/patients/${pid}/progress`),
        api(`/patients/${pid}/replies?limit=100`),
        api(`/patients/${pid}/reminders`),
      ]);
      const plan = runningPlan(plans.items);
      const last = latest.items[0] || null;
      Live.uploaded(last ? last.created_at : null);
      const item = last && plan ? plan.items.find((i) => i.exercise_slug === last.exercise_slug) : null;
      askAbout = await notAsked(last);
      lastSessionBlock(last, item, lib, last ? progress.points.filter((p) => p.exercise_slug === last.exercise_slug) : []);
      [advice, replies] = [suggestions.items, answers.items];
      adviceBlock();
      reminderBlock(reminders);
      planBlock(plan, lib, week.items);
      chartBlock(plan, lib, progress.points);
      feelingChart(lib, progress.points);
      Live.render();  // the new Start buttons follow the home computer's state
    } catch (err) { showError(err); }
  }
  load().then(() => exercises()).then((lib) => Live.init(pid, (slug) => exerciseName(lib, slug), (slug) => (lib[slug] || {}).instructions));
  Voice.init(pid);
  ReminderSettings.init(pid, async () => reminderBlock(await api(`/patients/${pid}/reminders`)));
  // a new result, new advice or a new plan shows without reloading the page; the home computer's set live
  Connection.attach(Coach.onChange(pid, load, Connection.watch({ "live.agent": Live.onAgent, "live.command": Live.onCommand,
    "live.progress": Live.onProgress, "session.stored": Live.onStored, open: Live.status })));
})();
