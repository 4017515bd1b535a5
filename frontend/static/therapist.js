/* Therapist dashboard: assigned patients with adherence, indicators and pending advice, most in need first. */
"use strict";
(() => {
  const { api, url, el, fmtDate, daysAgo, showError } = Coach;
  const INDICATORS = ["flexibility", "endurance", "strength", "balance"];

  /** Returns {score, level, reasons} for how much a patient needs attention now (higher = sooner). */
  function attention(row) {
    let score = 0;
    const reasons = [];
    if (row.pending_suggestions > 0) {
      score += 2 * row.pending_suggestions;
      reasons.push(`${row.pending_suggestions} suggestion${row.pending_suggestions > 1 ? "s" : ""} to review`);
    }
    const last = row.last_session;
    if (!last) { score += 4; reasons.push("no session yet"); }
    else {
      const d = daysAgo(last.started_at);
      if (d >= 7) { score += 3; reasons.push(`no session for ${d} days`); }
    }
    if (row.planned_this_week) {
      const weekday = (new Date().getUTCDay() + 6) % 7;  // 0 = Monday
      const expected = row.planned_this_week * (weekday + 1) / 7;
      if (row.sessions_this_week < expected - 0.5) {
        score += 3 * (1 - row.sessions_this_week / expected);
        reasons.push("behind this week's plan");
      }
    }
    const ind = row.latest_indicators || {};
    if (INDICATORS.some((k) => ind[k] && ind[k].score !== null && ind[k].quality_ok === false)) { score += 1; reasons.push("poor recording quality"); }
    const low = INDICATORS.filter((k) => ind[k] && ind[k].score !== null && ind[k].score < 50);
    if (low.length) { score += low.length; reasons.push("low " + low.join(", ")); }
    if (last && last.quality_ok === false && !reasons.includes("poor recording quality")) { score += 1; reasons.push("poor recording quality"); }
    return { score, level: score >= 5 ? "high" : score >= 2 ? "mid" : "low", reasons };
  }

  function indicatorCell(ind) {
    if (!ind || ind.score === null || ind.score === undefined) return el("td", { class: "muted", title: ind ? ind.basis : "no data" }, "—");
    const flag = ind.quality_ok === false ? el("span", { class: "flag", title: "data quality: the recording was poor; treat this score with care" }, "⚠") : null;
    const prev = ind.previous !== null && ind.previous !== undefined ? `; value ${ind.value}, earlier median ${ind.previous}` : "";
    return el("td", { title: `${ind.basis || ""}${prev}` },
      el("span", { class: "score" }, el("span", { class: "bar", "aria-hidden": "true" }, el("i", { style: `width:${Math.round(ind.score)}%` })),
        Math.round(ind.score), flag));
  }

  function row(r) {
    const a = attention(r);
    const href = url(`/therapist/patients/${r.patient_id}`);
    const last = r.last_session;
    const week = r.planned_this_week ? `${r.sessions_this_week} of ${r.planned_this_week} (${Math.round(100 * r.sessions_this_week / r.planned_this_week)}%)`
      : `${r.sessions_this_week} (no plan)`;
    const ind = r.latest_indicators || {};
    const tr = el("tr", { "data-patient-id": r.patient_id },
      el("td", {}, el("a", { href, class: "patient-link" }, r.full_name || r.email), el("span", { class: "reasons" }, r.email)),
      el("td", {}, el("span", { class: `pill ${a.level}` }, a.level === "high" ? "Now" : a.level === "mid" ? "Soon" : "OK"),
        el("span", { class: "reasons" }, a.reasons.join("; ") || "on track")),
      el("td", {}, last ? el("a", { href: url(`/therapist/sessions/${last.id}`), class: "session-link" }, fmtDate(last.started_at)) : "never",
        last ? el("span", { class: "reasons" }, `${(last.exercise_slug || "").replace(/_/g, " ")}${last.repetitions !== null ? ", " + last.repetitions + " reps" : ""}`) : null),
      el("td", {}, week),
      ...INDICATORS.map((k) => indicatorCell(ind[k])),
      el("td", {}, r.pending_suggestions ? el("a", { href: href + "#pending-h" }, String(r.pending_suggestions)) : "0"));
    tr._attention = a.score;
    return tr;
  }

  async function load() {
    const body = document.querySelector("#patients tbody");
    try {
      const rows = [];
      for (let offset = 0; ; offset += 200) {
        const page = await api(`/dashboard?limit=200&offset=${offset}`);
        rows.push(...page.items);
        if (rows.length >= page.total || !page.items.length) break;
      }
      const trs = rows.map(row).sort((a, b) => b._attention - a._attention || a.textContent.localeCompare(b.textContent));
      body.replaceChildren(...trs);
      if (!trs.length) body.append(el("tr", {}, el("td", { colspan: 9 }, "No patients are assigned to you yet.")));
    } catch (err) { body.replaceChildren(); showError(err); }
  }
  load();
})();
