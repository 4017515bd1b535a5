/* Spoken feedback during a live set: the browser's own speech synthesis (no server, no cloud) in the page's
 * language. live.js calls Voice.say(text) with exactly the text it shows; the patient's setting (on/off, volume) is
 * kept on the server (GET/PUT /patients/{id}/voice), so it follows the patient to any browser, and their therapist
 * can set it too. The control (#voice-control) is large: a toggle button and a volume slider. */
"use strict";
const Voice = (() => {
  const { api, el, showError } = Coach;
  const synth = window.speechSynthesis || null;
  let pid = null, enabled = true, volume = 1.0, saveTimer = null;

  /** Returns the synthesis voice for the page's language (the browser's default when it has none). */
  function voiceFor(tag) {
    const voices = synth ? synth.getVoices() : [];
    const lang = tag.toLowerCase();
    return voices.find((v) => v.lang.toLowerCase() === lang)
      || voices.find((v) => v.lang.toLowerCase().startsWith(lang.split("-")[0])) || null;
  }

  /** Speaks text (the same words the page shows) when the voice is on; queued after what is being said. */
  function say(text) {
    if (!enabled || !synth || !text || volume <= 0) return;
    const u = new SpeechSynthesisUtterance(text);
    u.lang = I18n.tag;
    u.volume = volume;
    u.rate = 0.9;  // a little slower than the default: older listeners, a few metres away
    const v = voiceFor(I18n.tag);
    if (v) u.voice = v;
    synth.speak(u);
  }

  function save() {
    clearTimeout(saveTimer);
    saveTimer = setTimeout(async () => {
      try { await api(`/patients/${pid}/voice`, { method: "PUT", body: { enabled, volume } }); }
      catch (err) { showError(err); }
    }, 400);
  }

  function render() {
    const box = document.getElementById("voice-control");
    if (!box) return;
    const toggle = el("button", { type: "button", class: "btn btn-big voice-toggle" + (enabled ? "" : " btn-quiet"), id: "voice-toggle",
      "aria-pressed": enabled ? "true" : "false", onclick: () => {
        enabled = !enabled;
        if (!enabled && synth) synth.cancel();  // quiet at once, not after the queue
        render(); save();
      } }, enabled ? I18n.t("Voice on") : I18n.t("Voice off"));
    const slider = el("input", { type: "range", id: "voice-volume", min: "0", max: "100", step: "10",
      value: String(Math.round(volume * 100)), disabled: !enabled,
      "aria-valuetext": I18n.t("{n} percent", { n: Math.round(volume * 100) }),
      onchange: (e) => { volume = +e.target.value / 100; render(); save(); } });
    const label = el("label", { for: "voice-volume" }, I18n.t("Volume"));
    const note = synth ? null : el("p", { class: "muted" }, I18n.t("This browser cannot speak; the page shows everything in writing."));
    box.replaceChildren(...[el("span", { class: "voice-what" }, I18n.t("Spoken counting during your exercises:")), toggle,
      el("span", { class: "voice-volume" }, label, slider), note].filter(Boolean));
    box.hidden = false;
  }

  /** Loads the patient's setting and shows the control. */
  async function init(patientId) {
    pid = patientId;
    try {
      const pref = await api(`/patients/${pid}/voice`);
      enabled = pref.enabled; volume = pref.volume;
    } catch (err) { showError(err); }
    render();
  }

  return { init, say, get enabled() { return enabled; } };
})();
