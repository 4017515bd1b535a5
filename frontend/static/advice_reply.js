/* Under each piece of advice on the patient's page: what the patient already answered, three large preset replies
 * ("Done", "It hurt", "Call me") and a short text box with Send (POST /patients/{id}/replies). The therapist sees the
 * answer at once as unread. patient.js shows AdviceReply.block(pid, advice, replies) in each advice item. */
"use strict";
const AdviceReply = (() => {
  const { api, el, kindMessage } = Coach;
  const MAX = 500;  // characters of a written reply (backend/replies/models.py MAX_TEXT)
  const PRESETS = { done: () => I18n.t("Done"), hurt: () => I18n.t("It hurt"), call_me: () => I18n.t("Call me") };
  const state = new Map();  // advice id -> {draft, sending, said, error}: kept while the page reloads its data
  let refresh = () => {};

  function stateOf(id) {
    if (!state.has(id)) state.set(id, { draft: "", sending: false, said: null, error: null });
    return state.get(id);
  }

  /** Returns one earlier answer in words: "It hurt — My knee" with its day, and whether the therapist read it. */
  function answered(r) {
    const words = [r.preset ? PRESETS[r.preset]() : null, r.text].filter(Boolean).join(" — ");
    return el("li", { "data-reply-id": r.id },
      I18n.t("You answered {day}: {answer}", { day: Coach.plainDay(r.created_at), answer: words }),
      r.read_at ? el("span", { class: "read" }, " · " + I18n.t("read by your therapist")) : null);
  }

  async function send(pid, adviceId, body) {
    const s = stateOf(adviceId);
    if (s.sending) return;  // the controls stay enabled (and focused) while one answer is on its way
    s.sending = true; s.error = null; refresh();
    try {
      await api(`/patients/${pid}/replies`, { method: "POST", body: { suggestion_id: adviceId, ...body } });
      s.said = I18n.t("Sent. Your therapist will see your answer.");
      if (body.text) s.draft = "";
    } catch (err) { s.error = kindMessage(err); s.said = null; }
    s.sending = false; refresh();
  }

  /** Returns the answers and reply controls of one piece of advice; replies: the patient's replies to it. */
  function block(pid, advice, replies) {
    const id = advice.id, s = stateOf(id), box = `reply-text-${id}`;
    const input = el("textarea", { id: box, rows: 2, maxlength: MAX,
      oninput: (e) => { s.draft = e.target.value; } });
    input.value = s.draft;
    const form = el("form", { class: "reply-form", onsubmit: (e) => {
      e.preventDefault();
      const text = s.draft.trim();
      if (!text) { s.error = I18n.t("Please write a few words first."); s.said = null; refresh(); return; }
      send(pid, id, { text });
    } },
    el("label", { for: box }, I18n.t("Or write a few words to your therapist")), input,
    el("button", { class: "btn btn-quiet", type: "submit", id: `reply-send-${id}` }, I18n.t("Send")));
    return el("div", { class: "reply", "data-advice-id": id },
      replies.length ? el("ul", { class: "answered" }, replies.map(answered)) : null,
      el("div", { class: "reply-presets", role: "group", "aria-label": I18n.t("Answer this advice") },
        Object.entries(PRESETS).map(([code, label]) => el("button", { type: "button", class: "btn btn-big btn-quiet",
          id: `reply-${code}-${id}`, "data-preset": code, onclick: () => send(pid, id, { preset: code }) }, label()))),
      form,
      s.said ? el("p", { class: "note", role: "status" }, s.said) : null,
      s.error ? el("p", { class: "alert", role: "alert" }, s.error) : null);
  }

  return { block, set onChange(f) { refresh = f; } };
})();
