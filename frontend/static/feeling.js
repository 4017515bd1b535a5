/* After each set, two large questions: pain now on the 0-10 numeric rating scale and effort on the Borg CR10 scale
 * (0-10), each with "skip"; the answers are stored with the session (PUT /sessions/{id}/feeling) and the therapist
 * sees them on the session page. live.js shows Feeling.block(sessionId) under the set's result; patient.js under
 * "Your last exercise" for a set of today not asked about there (recorded without the live panel, or closed). */
"use strict";
const Feeling = (() => {
  const { api, el, kindMessage } = Coach;
  const state = new Map();  // session id -> {pain, effort, saved, error, saving}
  const listeners = [];  // redraw the places that show a block (the live panel, "Your last exercise")
  const redraw = () => listeners.forEach((f) => f());

  function scale(id, label, ends, key, s) {
    const buttons = [];
    for (let n = 0; n <= 10; n++) {
      buttons.push(el("button", { type: "button", class: "scale-n" + (s[key] === n ? " chosen" : ""), "aria-pressed": s[key] === n ? "true" : "false",
        "aria-label": `${n}`, onclick: () => { s[key] = s[key] === n ? null : n; redraw(); } }, String(n)));
    }
    return el("fieldset", { class: "feeling-scale", id },
      el("legend", {}, label),
      el("div", { class: "scale-row" }, buttons),
      el("div", { class: "scale-ends", "aria-hidden": "true" }, el("span", {}, ends[0]), el("span", {}, ends[1])));
  }

  async function save(sessionId, s, skip) {
    s.saving = true; redraw();
    try {
      await api(`/sessions/${sessionId}/feeling`, { method: "PUT", body: skip ? { pain: null, effort: null } : { pain: s.pain, effort: s.effort } });
      s.saved = skip ? "skipped" : "saved"; s.error = null;
    } catch (err) { s.error = kindMessage(err); }
    s.saving = false; redraw();
  }

  /** Returns the questions for the stored session sessionId (or the thanks once answered). */
  function block(sessionId) {
    if (!state.has(sessionId)) state.set(sessionId, { pain: null, effort: null, saved: null, error: null, saving: false });
    const s = state.get(sessionId);
    if (s.saved === "saved") return el("p", { class: "lead", id: "feeling-thanks", role: "status" }, I18n.t("Thank you. Your therapist will see how it felt."));
    if (s.saved === "skipped") return null;
    return el("section", { class: "feeling", id: "feeling", "aria-labelledby": "feeling-h" },
      el("h3", { id: "feeling-h" }, I18n.t("How did it feel?")),
      scale("feeling-pain", I18n.t("Pain now"), [I18n.t("0 = no pain"), I18n.t("10 = worst pain")], "pain", s),
      scale("feeling-effort", I18n.t("How hard was it?"), [I18n.t("0 = not at all"), I18n.t("10 = as hard as it gets")], "effort", s),
      s.error ? el("p", { class: "alert", role: "alert" }, s.error) : null,
      el("div", { class: "feeling-actions" },
        el("button", { type: "button", class: "btn btn-big btn-good", id: "feeling-save", disabled: s.saving || (s.pain === null && s.effort === null),
          onclick: () => save(sessionId, s, false) }, I18n.t("Save")),
        el("button", { type: "button", class: "btn btn-big btn-quiet", id: "feeling-skip", disabled: s.saving,
          onclick: () => save(sessionId, s, true) }, I18n.t("Skip"))));
  }

  /** Returns whether the patient answered or skipped the questions of sessionId on this page. */
  function said(sessionId) { return Boolean(state.get(sessionId)?.saved); }

  return { block, said, listen: (f) => listeners.push(f) };
})();
