/* The therapist's session page: how the set felt to the patient (pain 0-10 NRS, effort Borg CR10), from
 * GET /sessions/{id}/feeling, in the line kept for it under the session's title (#session-feeling). */
"use strict";
(() => {
  const main = document.getElementById("main"), line = document.getElementById("session-feeling");
  if (!main || !line) return;
  Coach.api(`/sessions/${main.dataset.sessionId}/feeling`).then((f) => {
    const parts = [];
    if (f.pain !== null) parts.push(I18n.t("pain {pain} of 10 (numeric rating scale)", { pain: f.pain }));
    if (f.effort !== null) parts.push(I18n.t("effort {effort} of 10 (Borg CR10)", { effort: f.effort }));
    const text = f.answered_at === null ? I18n.t("The patient has not said how this set felt.")
      : parts.length ? I18n.t("How it felt, said by the patient: {answers}.", { answers: parts.join(", ") })
        : I18n.t("The patient skipped the questions on how it felt.");
    line.className = `${f.pain !== null && f.pain >= 5 ? "alert" : "lead"} feeling-line`;
    line.textContent = text;
  }).catch((err) => Coach.showError(err));
})();
