/* Therapist dashboard: assigned patients in the server's attention order, with reasons, indicator trends and advice,
 * and the patients' replies to advice that no therapist has read yet. */
"use strict";
(() => {
  const { api, url, el, fmtDate, showError, exercises, exerciseName } = Coach;
  // column names, repeated on each cell for narrow screens, where the rows stack as cards (app.css)
  const COLUMNS = [I18n.t("Patient"), I18n.t("Attention"), I18n.t("Latest session"), I18n.t("This week"),
    I18n.t("Flexibility"), I18n.t("Endurance"), I18n.t("Strength"), I18n.t("Balance"), I18n.t("To review")];
  const INDICATORS = ["flexibility", "endurance", "strength", "balance"];
  const INDICATOR_LABELS = { flexibility: COLUMNS[4], endurance: COLUMNS[5], strength: COLUMNS[6], balance: COLUMNS[7] };
  const LEVELS = { now: ["high", I18n.t("Now")], soon: ["mid", I18n.t("Soon")], ok: ["low", I18n.t("OK")] };
  const ARROWS = { up: "↑", down: "↓", flat: "→" };
  const SVG = "http://www.w3.org/2000/svg";

  /** Returns an SVG polyline of weekly medians (0..100, null = gap) or null with fewer than two points. */
  function sparkline(values) {
    const w = 56, h = 16, n = values.length;
    const points = values.map((v, i) => (v === null ? null : `${(i * w / Math.max(n - 1, 1)).toFixed(1)},${(h - 1 - v / 100 * (h - 2)).toFixed(1)}`))
      .filter((p) => p !== null);
    if (points.length < 2) return null;
    const svg = document.createElementNS(SVG, "svg");
    svg.setAttribute("viewBox", `-1 -1 ${w + 2} ${h + 2}`);
    svg.setAttribute("aria-hidden", "true");
    svg.setAttribute("focusable", "false");
    const line = document.createElementNS(SVG, "polyline");
    line.setAttribute("points", points.join(" "));
    svg.append(line);
    return svg;
  }

  /** Returns the trend of one indicator: a sparkline and an arrow, read out as the server's sentence. */
  function trend(t) {
    if (!t || !t.direction) return null;
    return el("span", { class: `trend ${t.direction}`, role: "img", "aria-label": t.text, title: t.text },
      sparkline(t.weekly_median), el("span", { class: "arrow" }, ARROWS[t.direction]));
  }

  /** Returns an indicator's measured number in the page's language with its unit (kinect_agent/analysis/indicators.py):
   *  flexibility degrees, endurance repetitions, strength s (sit-to-stand rise time) or °/s, balance m/s said in cm/s. */
  function measured(name, ind, v) {
    if (v === null || v === undefined) return "—";
    if (name === "flexibility") return I18n.t("{angle}°", { angle: I18n.number(v, 1) });
    if (name === "endurance") return I18n.number(v, 1);
    if (name === "strength") {
      return ind.basis && ind.basis.id === "strength_rise_time" ? I18n.t("{seconds} s", { seconds: I18n.number(v, 2) })
        : I18n.t("{speed} °/s", { speed: I18n.number(v, 1) });
    }
    return I18n.t("{speed} cm/s", { speed: I18n.number(100 * v, 1) });
  }

  function indicatorCell(name, ind, t, missing) {
    const tr = trend(t);
    const label = INDICATOR_LABELS[name];
    if (!ind || ind.score === null || ind.score === undefined) {
      const why = name === "balance" && missing ? el("span", { class: "reasons why-missing" }, missing) : null;
      return el("td", { class: "indicator", "data-label": label }, el("span", { class: "muted", title: ind && ind.basis ? ind.basis.text : I18n.t("no data") }, "—"), tr, why);
    }
    const flag = ind.quality_ok === false ? el("span", { class: "flag", title: I18n.t("data quality: the recording was poor; treat this score with care") }, "⚠") : null;
    const prev = ind.previous !== null && ind.previous !== undefined
      ? I18n.t("; value {value}, earlier median {previous}",
        { value: measured(name, ind, ind.value), previous: measured(name, ind, ind.previous) }) : "";
    const cms = (v) => I18n.number(100 * v, 1);
    const iv = name === "balance" && ind.interval && ind.value !== null
      ? el("span", { class: "reasons" }, I18n.t("{speed} cm/s (95 % {low}–{high})",
        { speed: cms(ind.value), low: cms(ind.interval[0]), high: cms(ind.interval[1]) })) : null;
    return el("td", { class: "indicator", "data-label": label, title: `${ind.basis ? ind.basis.text : ""}${prev}` },
      el("span", { class: "score" }, el("span", { class: "bar", "aria-hidden": "true" }, el("i", { style: `width:${Math.round(ind.score)}%` })),
        I18n.number(ind.score), flag), tr, iv);
  }

  function row(r, lib) {
    const href = url(`/therapist/patients/${r.patient_id}`);
    const last = r.last_session;
    const week = r.planned_this_week
      ? I18n.t("{done} of {planned} ({percent})", { done: r.sessions_this_week, planned: r.planned_this_week,
        percent: I18n.percent(r.sessions_this_week / r.planned_this_week) })
      : I18n.t("{done} (no plan)", { done: r.sessions_this_week });
    const ind = r.latest_indicators || {};
    const trends = r.indicator_trends || {};
    const [cls, label] = LEVELS[r.attention_level] || LEVELS.ok;
    return el("tr", { "data-patient-id": r.patient_id, "data-attention-score": r.attention_score, "data-attention-level": r.attention_level },
      el("td", { "data-label": COLUMNS[0] }, el("a", { href, class: "patient-link" }, r.full_name || r.email), el("span", { class: "reasons" }, r.email),
        r.unread_replies ? el("a", { href: href + "#replies-h", class: "new-replies" }, I18n.nt("{n} new reply", "{n} new replies", r.unread_replies)) : null),
      el("td", { class: "attention", "data-label": COLUMNS[1] }, el("span", { class: `pill ${cls}` }, label), " ",
        el("span", { class: "attention-score", title: I18n.t("attention score, 0–100") }, I18n.t("score {score}", { score: r.attention_score })),
        r.attention_reasons.length ? el("ul", { class: "reasons" }, ...r.attention_reasons.map((t) => el("li", {}, t)))
          : el("span", { class: "reasons" }, I18n.t("on track"))),
      el("td", { "data-label": COLUMNS[2] }, last ? el("a", { href: url(`/therapist/sessions/${last.id}`), class: "session-link" }, fmtDate(last.started_at)) : I18n.t("never"),
        last ? el("span", { class: "reasons" }, last.repetitions !== null
          ? I18n.nt("{exercise}, {n} rep", "{exercise}, {n} reps", last.repetitions, { exercise: exerciseName(lib, last.exercise_slug) })
          : exerciseName(lib, last.exercise_slug)) : null),
      el("td", { "data-label": COLUMNS[3] }, week),
      ...INDICATORS.map((k) => indicatorCell(k, ind[k], trends[k], r.balance_missing)),
      el("td", { class: "pending", "data-label": COLUMNS[8] },
        r.pending_suggestions ? el("a", { href: href + "#pending-h", "aria-label": I18n.nt("{n} suggestion to review", "{n} suggestions to review", r.pending_suggestions) }, String(r.pending_suggestions)) : "0"));
  }

  /** Shows the replies no therapist has read yet, newest first, each linked to its patient's page. */
  function repliesBlock(replies, rows) {
    const names = new Map(rows.map((r) => [r.patient_id, r.full_name || r.email]));
    const list = document.getElementById("unread-replies");
    list.replaceChildren(...replies.items.map((r) => RepliesView.item(r, { isNew: true,
      who: el("a", { href: url(`/therapist/patients/${r.patient_id}#replies-h`) }, names.get(r.patient_id) || I18n.t("patient {id}", { id: r.patient_id })) })));
    if (!replies.items.length) list.append(el("li", { class: "muted" }, I18n.t("No unread replies.")));
    if (replies.total > replies.items.length) list.append(el("li", { class: "muted" }, I18n.t("and {count} more", { count: replies.total - replies.items.length })));
  }

  async function load() {
    const body = document.querySelector("#patients tbody");
    try {
      const lib = await exercises().catch(() => ({}));
      const rows = [];
      for (let offset = 0; ; offset += 200) {
        const page = await api(`/dashboard?limit=200&offset=${offset}`);
        rows.push(...page.items);
        if (rows.length >= page.total || !page.items.length) break;
      }
      body.replaceChildren(...rows.map((r) => row(r, lib)));  // the server's order: attention score, highest first, then name
      repliesBlock(await api("/replies?unread=true&limit=20"), rows);
      if (!rows.length) body.append(el("tr", {}, el("td", { colspan: 9 }, I18n.t("No patients are assigned to you yet."))));
    } catch (err) { body.replaceChildren(); showError(err); }
  }
  load();
  Coach.onChange(null, load);  // new sessions, advice and replies re-rank the list without reloading the page
})();
