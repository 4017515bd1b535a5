/* Therapist pages: one reply of a patient to advice, as a list item (the dashboard's unread list, the patient page's
 * conversation). Therapist pages are English for now; the patient's page says the presets in their language. */
"use strict";
const RepliesView = (() => {
  const { el, fmtDateTime } = Coach;
  const PRESETS = { done: "Done", hurt: "It hurt", call_me: "Call me" };

  /** Returns what the patient said: the preset's words and their own, e.g. "It hurt — my knee". */
  function words(r) { return [r.preset ? PRESETS[r.preset] : null, r.text].filter(Boolean).join(" — "); }

  /** Returns one reply as an <li>: optional "new" pill and who (a link), what they said, the advice answered, when. */
  function item(r, { isNew = false, who = null } = {}) {
    const advice = r.suggestion_text.length > 140 ? r.suggestion_text.slice(0, 139) + "…" : r.suggestion_text;
    return el("li", { "data-reply-id": r.id, class: isNew ? "unread" : null },
      isNew ? el("span", { class: "pill new" }, "new") : null, isNew ? " " : null, who, who ? ": " : null,
      el("span", { class: "answer" }, words(r)),
      el("span", { class: "to" }, `to the advice “${advice}” · ${fmtDateTime(r.created_at)}`));
  }

  return { words, item };
})();
