/* Therapist pages: one reply of a patient to advice, as a list item (the dashboard's unread list, the patient page's
 * conversation), in the therapist page's language (the presets' words are the ones the patient's page shows). */
"use strict";
const RepliesView = (() => {
  const { el, fmtDateTime } = Coach;
  const PRESETS = { done: I18n.t("Done"), hurt: I18n.t("It hurt"), call_me: I18n.t("Call me") };

  /** Returns what the patient said: the preset's words and their own, e.g. "It hurt — my knee". */
  function words(r) { return [r.preset ? PRESETS[r.preset] : null, r.text].filter(Boolean).join(" — "); }

  /** Returns one reply as an <li>: optional "new" pill and who (a link), what they said, the advice answered, when. */
  function item(r, { isNew = false, who = null } = {}) {
    const advice = r.suggestion_text.length > 140 ? r.suggestion_text.slice(0, 139) + "…" : r.suggestion_text;
    return el("li", { "data-reply-id": r.id, class: isNew ? "unread" : null },
      isNew ? el("span", { class: "pill new" }, I18n.t("new")) : null, isNew ? " " : null, who, who ? ": " : null,
      el("span", { class: "answer" }, words(r)),
      el("span", { class: "to" }, I18n.t("to the advice “{advice}” · {when}", { advice, when: fmtDateTime(r.created_at) })));
  }

  return { words, item };
})();
