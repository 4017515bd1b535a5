/* Therapist's view of one session: angle curves (raw and filtered) with the repetitions marked, the repetition
   table, movement, reach of each arm, data quality with the tracking-error strip and camera advice, processing. */
"use strict";
(() => {
  const { api, url, el, fmtDate, fmtDateTime, showError } = Coach;
  const main = document.getElementById("main");
  const sid = main.dataset.sessionId;
  const RAW = "#c0392b", FILTERED = "#0b4f9c", LEFT = "#0b4f9c", RIGHT = "#b8336a";
  const JOINT_WORDS = {
    ROOT: I18n.t("pelvis"), SPINE: I18n.t("spine"), NECK: I18n.t("neck"), HEAD: I18n.t("head"), SHO: I18n.t("shoulder"),
    ELB: I18n.t("elbow"), WRI: I18n.t("wrist"), HAN: I18n.t("hand"), HIP: I18n.t("hip"), KNE: I18n.t("knee"),
    ANK: I18n.t("ankle"), FOO: I18n.t("foot"),
  };

  function jointName(j, short) {
    const [base, side] = j.split("_");
    const word = JOINT_WORDS[base] || base.toLowerCase();
    if (!side) return word;
    // TRANSLATORS: "L knee": the short name of a left joint in the tracking-error strip
    if (short) return side === "L" ? I18n.t("L {joint}", { joint: word }) : I18n.t("R {joint}", { joint: word });
    return side === "L" ? I18n.t("left {joint}", { joint: word }) : I18n.t("right {joint}", { joint: word });
  }
  const SIDE_WORDS = { left: I18n.t("left"), right: I18n.t("right"), both: I18n.t("both sides"), center: "—" };
  const sideWord = (s) => SIDE_WORDS[s] || s;
  const secs = (x) => (x === null || x === undefined ? "—" : I18n.t("{seconds} s", { seconds: I18n.number(x, 1) }));
  const deg = (x) => (x === null || x === undefined ? "—" : `${I18n.number(x, 1)}°`);
  const angleSide = (name) => ({ _L: "left", _R: "right" }[name.slice(-2)] || "center");
  const wholeSecs = (x) => I18n.t("{seconds} s", { seconds: I18n.number(x) });

  function stat(label, value, note) {
    return [el("div", { class: "stat" }, el("dt", {}, label), el("dd", {}, value, note ? el("span", { class: "reasons" }, note) : null))];
  }

  /** Returns "a–b° (95 %)" for an interval [a, b], or null. */
  const ci = (iv) => (iv ? I18n.t("{low}–{high}° (95 %)", { low: I18n.number(iv[0]), high: I18n.number(iv[1]) }) : null);

  /** Returns the stats of the defining angle's full range and peak (the end its repetitions reach, as in the
      repetition table) with their 95 % intervals, or the reason they are withheld. */
  function intervalStats(d) {
    const a = d.uncertainty && d.defining_angle ? d.uncertainty.angles[d.defining_angle] : null;
    if (!a) return [];
    const low = d.uncertainty.peak_end === "min";
    const peak = low ? a.min_deg : a.max_deg, peakCi = low ? a.min_ci95 : a.max_ci95;
    const note = (iv) => (a.withheld ? I18n.t("no interval: {reason}", { reason: a.withheld }) : ci(iv));
    return [...stat(I18n.t("Full range"), deg(a.range_deg), note(a.range_ci95)), ...stat(I18n.t("Peak angle"), deg(peak), note(peakCi))];
  }

  /** Returns the balance stat: sway velocity in cm/s with its 95 % interval, or why it is not measured. */
  function balanceStat(d) {
    const b = d.balance;
    if (!b) return stat(I18n.t("Balance (sway)"), I18n.t("Not measured"), d.balance_missing);
    const iv = b.sway_velocity_95;
    const standing = I18n.t("over {seconds} s standing", { seconds: I18n.number(b.standing_s) });
    const note = iv ? I18n.t("{low}–{high} cm/s (95 %), {standing}", { low: I18n.number(100 * iv[0], 1),
      high: I18n.number(100 * iv[1], 1), standing }) : standing;
    const said = metricFlagged(d, "balance") ? I18n.t("{note}; from one camera: see the limits above", { note }) : note;
    return stat(I18n.t("Balance (sway)"), I18n.t("{speed} cm/s", { speed: I18n.number(100 * b.sway_velocity_m_s, 1) }), said);
  }
  /** Returns whether the recording's device and view cannot support the metric (the limits box lists it). */
  const metricFlagged = (d, name) => d.validity.metrics.some((m) => m.name === name && !m.valid);
  const romValid = (d) => !metricFlagged(d, "rom");

  function keyNumbers(d) {
    const total = (d.moving_time_s || 0) + (d.rest_time_s || 0);
    const moving = d.moving_time_s === null ? "—" : wholeSecs(d.moving_time_s);
    const reps = d.uncertainty && d.uncertainty.repetitions;
    const repNote = reps && reps.ambiguous ? I18n.t("uncertain: {low}–{high}", { low: reps.low, high: reps.high }) : null;
    document.getElementById("numbers").replaceChildren(
      ...stat(I18n.t("Repetitions"), d.repetition_count === null ? "—" : I18n.number(d.repetition_count), repNote),
      ...stat(I18n.t("Range of motion"), deg(d.rom_deg), d.rom_deg_withheld || (romValid(d) ? I18n.t("median of the repetitions")
        : I18n.t("median of the repetitions; not reliable from this view: see the limits above"))),
      ...intervalStats(d),
      ...stat(I18n.t("Duration"), wholeSecs(d.duration_s), I18n.nt("{n} frame", "{n} frames", d.n_frames, { n: I18n.number(d.n_frames) })),
      ...stat(I18n.t("Moving"), moving, total ? I18n.t("{percent} of the time", { percent: I18n.percent(d.moving_time_s / total) }) : null),
      ...stat(I18n.t("Time per repetition"), secs(d.tempo_s_per_rep)),
      ...balanceStat(d),
      ...stat(I18n.t("Data quality"), I18n.t("{score} / 100", { score: d.quality.score }), d.quality.low ? I18n.t("low: read with care") : I18n.t("good")),
      ...stat(I18n.t("Recorded with"), d.recorded_with.label, deviceText(d.recorded_with) === d.recorded_with.label ? null : deviceText(d.recorded_with).slice(d.recorded_with.label.length + 2)));
  }

  /** Returns the repetitions an angle's chart marks: those of its side, and those of both sides. */
  function repsOf(d, angle) {
    const side = angleSide(angle);
    return d.repetitions.filter((r) => r.side === side || r.side === "both" || r.side === "center" || side === "center");
  }

  function curveTable(raw, filt) {
    const byT = new Map();
    raw.t_s.forEach((t, i) => byT.set(t, [t, raw.deg[i], null]));
    filt.t_s.forEach((t, i) => { const row = byT.get(t) || [t, null, null]; row[2] = filt.deg[i]; byT.set(t, row); });
    return [...byT.values()].sort((a, b) => a[0] - b[0]);
  }

  function curveFigure(d, angle) {
    const raw = d.curves.find((c) => c.angle === angle && c.kind === "raw");
    const filt = d.curves.find((c) => c.angle === angle && c.kind !== "raw");
    const reps = repsOf(d, angle);
    const name = raw.angle_label;  // the curves' words come in the reader's language
    const shapes = reps.map((r) => ({ type: "rect", xref: "x", yref: "paper", x0: r.start_s, x1: r.end_s, y0: 0, y1: 1,
      fillcolor: "rgba(11, 79, 156, 0.08)", line: { color: "rgba(11, 79, 156, 0.55)", width: 1, dash: "dot" }, layer: "below" }));
    // labels on two staggered rows, so that neighbours do not overlap on a phone (zoom in to separate more)
    const annotations = reps.map((r, i) => ({ x: (r.start_s + r.end_s) / 2, y: 1, xref: "x", yref: "paper", yanchor: "bottom",
      yshift: i % 2 ? 18 : 0, text: r.rom_deg === null ? "—" : `${I18n.number(r.rom_deg)}°`, showarrow: false, font: { size: 14, color: "#0b3a72" } }));
    return Plots.figure({
      title: `${name[0].toUpperCase()}${name.slice(1)} (°)`,
      traces: [
        { x: raw.t_s, y: raw.deg, name: raw.kind_label, type: "scatter", mode: "lines", line: { color: RAW, width: 1.2 }, opacity: 0.8,
          hovertemplate: I18n.t("%{x:.1f} s: %{y:.1f}° ({kind})", { kind: raw.kind_label }) + "<extra></extra>" },
        { x: filt.t_s, y: filt.deg, name: filt.kind_label, type: "scatter", mode: "lines", line: { color: FILTERED, width: 2.5 },
          hovertemplate: I18n.t("%{x:.1f} s: %{y:.1f}° ({kind})", { kind: filt.kind_label }) + "<extra></extra>" },
      ],
      layout: { shapes, annotations, margin: { t: 48 }, xaxis: { title: { text: I18n.t("time (s)") } }, yaxis: { title: { text: I18n.t("angle (°)") } },
        legend: { y: -0.28, yanchor: "top" } },
      table: { caption: I18n.t("{angle}: angle over time, {raw} and {kind}", { angle: name, raw: raw.kind_label, kind: filt.kind_label }),
        columns: [I18n.t("time (s)"), I18n.t("{kind} (°)", { kind: raw.kind_label }), I18n.t("{kind} (°)", { kind: filt.kind_label })],
        rows: curveTable(raw, filt) },
    });
  }

  function curves(d) {
    const box = document.getElementById("curves");
    box.replaceChildren();
    if (!d.curves.length) { box.append(el("p", { class: "muted" }, I18n.t("This exercise has no angle to show."))); return; }
    for (const angle of d.angles) box.append(curveFigure(d, angle));
  }

  /** Returns a repetition's peak cell: the angle, or "—" and why it is withheld (as the key numbers say it). */
  const peakCell = (r) => el("td", {}, deg(r.peak_deg), r.withheld ? el("span", { class: "reasons" }, r.withheld) : null);

  function repTable(d) {
    const body = document.querySelector("#reps tbody");
    body.replaceChildren(...d.repetitions.map((r) => el("tr", r.withheld ? { class: "withheld" } : {},
      el("td", {}, String(r.index + 1)), el("td", {}, sideWord(r.side)), el("td", {}, secs(r.start_s)), el("td", {}, secs(r.end_s)),
      el("td", {}, secs(r.duration_s)), el("td", {}, deg(r.rom_deg)), peakCell(r),
      el("td", {}, r.peak_speed_deg_s === null ? "—" : `${I18n.number(r.peak_speed_deg_s)}°/s`))));
    if (!d.repetitions.length) body.append(el("tr", {}, el("td", { colspan: 8, class: "muted" }, I18n.t("No repetition was found in this session."))));
  }

  function movement(d) {
    const total = (d.moving_time_s || 0) + (d.rest_time_s || 0);
    document.getElementById("moving-rest").textContent = d.moving_time_s === null ? I18n.t("Moving time is not known for this session.")
      : I18n.t("Moving {moving} s ({percent}), resting {resting} s.", { moving: I18n.number(d.moving_time_s),
        percent: I18n.percent(d.moving_time_s / total), resting: I18n.number(d.rest_time_s) });
    const top = d.most_moving_joints.slice(0, 6);
    const box = document.getElementById("most-moving");
    if (!top.length) { box.replaceChildren(); return; }
    box.replaceChildren(Plots.figure({
      title: I18n.t("Joints that moved most (distance travelled, m)"),
      traces: [{ type: "bar", orientation: "h", x: top.map((j) => j.path_m), y: top.map((j) => jointName(j.joint)),
        marker: { color: FILTERED }, hovertemplate: "%{y}: %{x:.2f} m<extra></extra>" }],
      layout: { yaxis: { autorange: "reversed" }, xaxis: { title: { text: I18n.t("metres") } }, showlegend: false },
      height: 300,
      table: { columns: [I18n.t("joint"), I18n.t("distance (m)")], rows: top.map((j) => [jointName(j.joint), I18n.number(j.path_m, 2)]) },
    }));
  }

  function pct(x) {
    if (x === null) return "—";
    return new Intl.NumberFormat(I18n.tag, { style: "percent", maximumFractionDigits: x < 0.1 ? 1 : 0 }).format(x);
  }

  function quality(d) {
    const q = d.quality;
    document.getElementById("quality-score").replaceChildren(el("strong", {}, I18n.t("{score} / 100", { score: q.score })), " — ",
      q.low ? I18n.t("low: the numbers of this session may be off.") : I18n.t("good enough to trust the numbers."));
    document.getElementById("quality-parts").replaceChildren(...q.parts.map((p) => el("li", {},
      el("span", { class: "score" }, el("span", { class: "bar", "aria-hidden": "true" }, el("i", { style: `width:${p.score || 0}%` })),
        el("span", {}, I18n.t("{part}:", { part: p.label }) + " ", el("strong", {}, p.name === "segment_spread_mm"
          ? (p.value === null ? "—" : I18n.t("{length} mm", { length: I18n.number(p.value, 1) })) : pct(p.value)),
          " (", I18n.t("{score} / 100", { score: p.score === null ? "—" : p.score }), ")")))));
    const box = document.getElementById("advice");
    const items = q.advice.map((a) => el("li", { "data-code": a.code }, a.text));
    const reasons = q.analysis_ok === false && q.analysis_reasons.length
      ? el("p", { class: "small" }, I18n.t("The analysis also noted: {reasons}.", { reasons: q.analysis_reasons.join("; ") })) : null;
    const extra = reasons ? [reasons] : [];
    if (items.length) box.replaceChildren(el("h3", {}, I18n.t("Camera advice")), el("ul", { class: "advice" }, ...items), ...extra);
    else if (q.low) box.replaceChildren(el("p", {}, I18n.t("The score is low, but the camera set-up itself looked fine: the patient was at a good distance and in view.")), ...extra);
    else box.replaceChildren(el("p", { class: "muted" }, I18n.t("The camera set-up looked fine.")), ...extra);
  }

  function stripFigure(d) {
    const s = d.quality.outlier_strip;
    const names = s.joints.map((j) => jointName(j, true));  // "L knee": short, so the strip keeps its width on a phone
    const rows = s.joints.map((j, k) => {
      const vals = s.prob[k].filter((v) => v !== null);
      const flagged = s.prob[k].map((v, i) => (v !== null && v > s.threshold ? s.t_s[i] : null)).filter((t) => t !== null);
      return [jointName(j), vals.length ? I18n.number(Math.max(...vals), 2) : I18n.t("not seen"),
        I18n.t("{count} of {total}", { count: flagged.length, total: s.t_s.length }),
        flagged.length ? flagged.slice(0, 8).map((t) => secs(t)).join(", ") + (flagged.length > 8 ? ", …" : "") : I18n.t("none")];
    });
    document.getElementById("strip").replaceChildren(Plots.figure({
      title: I18n.t("Chance that a joint's reading was a tracking error"),
      traces: [{ type: "heatmap", z: s.prob, x: s.t_s, y: names, zmin: 0, zmax: 1, hoverongaps: false,
        colorscale: [[0, "#ffffff"], [0.5, "#f3d27a"], [0.9, "#d66e14"], [1, "#7a0d12"]],
        colorbar: { orientation: "h", x: 0, xanchor: "left", y: 1.01, yanchor: "bottom", len: 1, thickness: 10,
          tickvals: [0, 0.5, 1], ticktext: [I18n.t("fine"), I18n.percent(0.5), I18n.t("error")] },
        hovertemplate: "%{y}, %{x:.1f} s: %{z:.0%}<extra></extra>" }],
      layout: { yaxis: { autorange: "reversed" }, xaxis: { title: { text: I18n.t("time (s)") } }, margin: { t: 70 } },
      height: 24 * names.length + 160,
      table: { caption: I18n.t("Tracking errors per joint (a column is {seconds} s; error when the chance is above {percent})",
        { seconds: I18n.number(s.column_s, 2), percent: I18n.percent(s.threshold) }),
        columns: [I18n.t("joint"), I18n.t("highest chance"), I18n.t("columns with an error"), I18n.t("when")], rows },
    }));
  }

  function workspace(d) {
    const card = document.getElementById("workspace-card");
    if (!d.workspace) { card.hidden = true; return; }
    card.hidden = false;
    const arms = [["left", LEFT, 1], ["right", RIGHT, -1]].filter(([side]) => d.workspace[side]);
    const HANDS = { left: I18n.t("left hand"), right: I18n.t("right hand") };
    const ARMS = { left: I18n.t("Left arm"), right: I18n.t("Right arm") };
    const circle = { type: "circle", xref: "x", yref: "y", x0: -1, x1: 1, y0: -1, y1: 1, line: { color: "#767676", dash: "dot" } };
    const view = (title, xKey, xSign, xTitle) => Plots.figure({
      title,
      traces: arms.map(([side, color, mirror]) => ({
        type: "scatter", mode: "markers", name: HANDS[side], marker: { color, size: 5, opacity: 0.6 },
        x: d.workspace[side][xKey].map((v) => (v === null ? null : v * (xSign ? mirror : 1))), y: d.workspace[side].up,
        hovertemplate: I18n.t("{hand}: %{x:.2f}, %{y:.2f} arm lengths", { hand: HANDS[side] }) + "<extra></extra>" })),
      layout: { shapes: [circle], xaxis: { title: { text: xTitle }, range: [-1.25, 1.25], zeroline: true, constrain: "domain" },
        yaxis: { title: { text: I18n.t("up (arm lengths)") }, range: [-1.25, 1.25], scaleanchor: "x" }, margin: { t: 40 } },
      height: 420,
      table: { columns: [I18n.t("hand"), xTitle.replace("<br>", " "), I18n.t("up (arm lengths)")],
        rows: arms.flatMap(([side, , mirror]) => d.workspace[side][xKey].map((v, i) => [HANDS[side],
          v === null ? null : I18n.number(v * (xSign ? mirror : 1), 2), d.workspace[side].up[i]])) },
    });
    const numbers = el("ul", { class: "small" }, ...arms.map(([side]) => {
      const w = d.workspace[side];
      return el("li", {}, I18n.t("{arm}: reached {area} of the area in front of the shoulder, {volume} of its volume (arm length {length} m).",
        { arm: ARMS[side], area: pct(w.area_ratio), volume: pct(w.volume_ratio), length: I18n.number(w.arm_length_m, 2) }));
    }));
    document.getElementById("workspace").replaceChildren(
      view(I18n.t("Seen from the front"), "outward", true, I18n.t("sideways, arm lengths<br>(← patient's right · left →)")),
      view(I18n.t("Seen from the side"), "forward", false, I18n.t("forward (arm lengths)")), numbers);
  }

  function processing(d) {
    const p = d.processing;
    // a box that scrolls: reachable and scrollable with the keyboard, named for screen readers
    const pre = (obj, name) => el("pre", { class: "params", tabindex: 0, role: "region", "aria-label": name }, JSON.stringify(obj, null, 2));
    document.getElementById("processing-body").replaceChildren(
      el("dl", { class: "kv" },
        el("dt", {}, I18n.t("Server version")), el("dd", {}, p.version || "—"),
        el("dt", {}, I18n.t("Numbers from")), el("dd", {}, p.analysis === "stored" ? I18n.t("the analysis stored at upload") : I18n.t("an analysis made now (none was stored)")),
        el("dt", {}, I18n.t("Measured on")), el("dd", {}, d.measured_on === "filtered" ? I18n.t("the filtered recording") : I18n.t("the raw recording")),
        el("dt", {}, I18n.t("Uncertainty")), el("dd", {}, d.uncertainty_note)),
      el("h3", {}, I18n.t("Filter steps")), el("ol", {}, ...(p.filter_history.length ? p.filter_history.map((h) => el("li", {}, h)) : [el("li", {}, I18n.t("none recorded"))])),
      el("h3", {}, I18n.t("Parameters stored with the session")), pre(p.params, I18n.t("Parameters stored with the session")),
      el("h3", {}, I18n.t("Parameters in the session file")), pre(p.file_params, I18n.t("Parameters in the session file")));
  }

  const METRIC_WORDS = {
    rom: I18n.t("Range of motion"), repetitions: I18n.t("Repetitions"), moving_time: I18n.t("Moving time"),
    tempo: I18n.t("Time per repetition"), workspace: I18n.t("Reach of each arm"), balance: I18n.t("Balance and sway"),
    joint_paths: I18n.t("Distance joints travelled"),
  };
  /** Returns a metric's name in words; an angle's internal name ("knee_flexion_L") with its side in words. */
  function metricName(name) {
    if (METRIC_WORDS[name]) return METRIC_WORDS[name];
    const words = name.replace(/_/g, " ");
    if (/ L$/.test(words)) return I18n.t("{angle} (left)", { angle: words.slice(0, -2) });
    if (/ R$/.test(words)) return I18n.t("{angle} (right)", { angle: words.slice(0, -2) });
    return words;
  }
  const VIEW_WORDS = { front: I18n.t("from the front"), side: I18n.t("from the side"), oblique: I18n.t("at an angle"),
    unknown: I18n.t("from an unknown angle") };

  /** Returns the device in words, with the pose model and its frame rate for an ordinary camera. */
  function deviceText(r) {
    const parts = [r.label];
    if (r.model) parts.push(I18n.t("model {model}", { model: r.model.replace(/\.task$/, "") }));
    if (r.fps_achieved) parts.push(I18n.t("{rate} images/s", { rate: I18n.number(r.fps_achieved) }));
    return parts.join(", ");
  }

  /** Shows the box of metrics this device and view cannot support, with the reasons (hidden when none). */
  function limits(d) {
    const v = d.validity;
    const box = document.getElementById("limits");
    const flagged = v.metrics.filter((m) => !m.valid);
    box.hidden = !flagged.length;
    if (!flagged.length) return;
    document.getElementById("limits-intro").textContent =
      I18n.t("Recorded with: {device}, filmed {view}.", { device: deviceText(d.recorded_with), view: VIEW_WORDS[v.view] || v.view }) + " " +
      I18n.t("One camera sees movements across the image well and movements towards it poorly. " +
        "Repetitions and the angles marked valid can be used; read these with care:");
    document.getElementById("limits-list").replaceChildren(...flagged.map((m) =>
      el("li", { "data-metric": m.name }, el("strong", {}, `${metricName(m.name)}: `), m.reason)));
  }

  /** Shows a session whose recording the retention period removed: the date, in plain words, and the kept numbers. */
  async function removed() {
    document.getElementById("session-body").hidden = true;
    const s = await api(`/sessions/${sid}`);
    const name = s.exercise_slug ? s.exercise_slug.replace(/_/g, " ") : I18n.t("Session");
    document.getElementById("session-title").textContent = `${name[0].toUpperCase()}${name.slice(1)} · ${fmtDateTime(s.started_at)}`;
    document.getElementById("session-sub").textContent = "";
    document.getElementById("removed-text").textContent = s.file_removed_at
      ? I18n.t("This session was removed on {day} under the clinic's retention policy.",
        { day: fmtDate(s.file_removed_at, { day: "numeric", month: "long", year: "numeric" }) })
      : I18n.t("This session was removed under the clinic's retention policy.");
    document.getElementById("removed-numbers").replaceChildren(
      ...stat(I18n.t("Repetitions"), s.repetitions === null ? "—" : I18n.number(s.repetitions)),
      ...stat(I18n.t("Range of motion"), deg(s.rom_deg), s.metrics && s.metrics.rom_deg_withheld ? s.metrics.rom_deg_withheld.text : null),
      ...stat(I18n.t("Duration"), wholeSecs(s.duration_s), I18n.nt("{n} frame", "{n} frames", s.n_frames, { n: I18n.number(s.n_frames) })),
      ...stat(I18n.t("Data quality"), s.quality_ok === null ? "—" : s.quality_ok ? I18n.t("good") : I18n.t("low")));
    document.getElementById("removed").hidden = false;
    const back = document.getElementById("back");
    back.href = url(`/therapist/patients/${s.patient_id}`);
    api(`/patients/${s.patient_id}`).then((p) => { back.textContent = `← ${p.full_name || p.email}`; }).catch(() => {});
  }

  // the curves and numbers are prepared once by a worker: while they are, the page says so and asks again
  const stateBox = document.getElementById("detail-state");
  const POLL_MS = 1500;
  let waiting = false;  // asked and told "being prepared" at least once
  function say(kind, text) { stateBox.className = kind; stateBox.textContent = text; stateBox.hidden = false; }

  async function load() {
    try {
      const d = await api(`/sessions/${sid}/detail`);
      if (d.state === "failed") {
        say("alert", I18n.t("The session's curves and numbers could not be prepared.") + " " + d.detail);
        document.getElementById("session-sub").textContent = "";
        return;
      }
      if (d.state === "preparing") {
        waiting = true;
        say("note", I18n.t("The session's curves and numbers are being prepared.") + " " + d.detail);
        setTimeout(load, POLL_MS);
        return;
      }
      stateBox.hidden = true;
      const name = d.exercise_name || (d.exercise_slug || I18n.t("Exercise")).replace(/_/g, " ");
      document.getElementById("session-title").textContent = `${name} · ${fmtDateTime(d.started_at)}`;
      document.title = `${name}, ${fmtDateTime(d.started_at)} · Kinect Home Coach`;
      document.getElementById("session-sub").textContent = d.status === "processed" ? ""
        : d.error || I18n.t("The analysis could not use this recording.");  // d.error: in the reader's words
      limits(d);
      keyNumbers(d);
      curves(d);
      repTable(d);
      movement(d);
      quality(d);
      workspace(d);
      stripFigure(d);
      processing(d);
      api(`/patients/${d.patient_id}`).then((patient) => {
        const back = document.getElementById("back");
        back.href = url(`/therapist/patients/${d.patient_id}`);
        back.textContent = `← ${patient.full_name || patient.email}`;
        document.getElementById("session-sub").textContent ||= I18n.t("Session of {name}", { name: patient.full_name || patient.email });
      }).catch(() => {});
    } catch (err) {
      if (waiting && (err.status === 0 || err.status >= 500)) {  // lost while waiting: say so, ask again
        say("alert", I18n.t("The server could not be asked whether the session is ready ({reason}); trying again.", { reason: err.detail || err.message }));
        setTimeout(load, POLL_MS * 2);
        return;
      }
      stateBox.hidden = true;
      if (err.error === "SessionFileRemoved") {
        try { await removed(); return; } catch (again) { err = again; }
      }
      document.getElementById("session-sub").textContent = I18n.t("This session cannot be shown.");
      document.getElementById("session-body").hidden = true;  // no empty sections, downloads or replay under the error
      showError(err);
    }
  }
  load();
})();
