/* The therapist's side of the patient's voice (voice.js): on/off and volume of the spoken counting on the patient's
 * page, set beside the plan (GET/PUT /patients/{id}/voice; the patient can change it too). */
"use strict";
(() => {
  const form = document.getElementById("voice-setting");
  if (!form) return;
  const pid = document.getElementById("main").dataset.patientId;
  const on = document.getElementById("voice-setting-on"), volume = document.getElementById("voice-setting-volume");
  const msg = document.getElementById("voice-setting-msg");
  const show = (pref) => { on.checked = pref.enabled; volume.value = String(Math.round(pref.volume * 100)); volume.disabled = !pref.enabled; };
  on.addEventListener("change", () => { volume.disabled = !on.checked; });
  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    msg.textContent = "";
    try {
      show(await Coach.api(`/patients/${pid}/voice`, { method: "PUT", body: { enabled: on.checked, volume: +volume.value / 100 } }));
      msg.textContent = I18n.t("Saved — the patient's page uses it from the next set.");
    } catch (err) { msg.textContent = Coach.kindMessage(err); }
  });
  Coach.api(`/patients/${pid}/voice`).then((pref) => { show(pref); form.hidden = false; }).catch((err) => Coach.showError(err));
})();
