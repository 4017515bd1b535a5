/* The patient's reminder settings on their page (#reminder-settings, rendered by the server with their current
 * values): the time zone of their reminder times, with the browser's own zone offered first, and reminder e-mails
 * on or off. Each change is saved at once through PATCH /patients/{id}, and said in the patient's language. */
"use strict";
const ReminderSettings = (() => {
  const { api, kindMessage, showError } = Coach;

  /** Returns the browser's IANA time zone ("Europe/Berlin"), or "" when it does not say. */
  function deviceZone() {
    try { return Intl.DateTimeFormat().resolvedOptions().timeZone || ""; } catch (err) { return ""; }
  }

  /** Moves the browser's own zone to the top of the select, named as this device's (when the server knows it). */
  function offerDeviceZone(select) {
    const zone = deviceZone();
    const option = [...select.options].find((o) => o.value === zone);
    if (!option) return;
    option.textContent = I18n.t("{zone} (this device)", { zone: zone.replace(/_/g, " ") });
    select.prepend(option);
  }

  /** Sends one change; says what happened; puts the control back as it was when it was not saved. */
  async function save(pid, body, said, undo, onSaved) {
    const status = document.getElementById("remind-saved");
    status.className = "lead";
    status.textContent = I18n.t("Saving…");
    try {
      await api(`/patients/${pid}`, { method: "PATCH", body });
    } catch (err) {
      undo();
      status.className = "lead alert";
      status.textContent = I18n.t("Not saved: {reason}", { reason: kindMessage(err) });
      return;
    }
    status.className = "lead note";
    status.textContent = said;
    try { await onSaved(); } catch (err) { showError(err); }
  }

  /** Wires the settings block of patient pid; onSaved() runs after each saved change (the page shows the reminder
   *  again, in the new time zone). */
  function init(pid, onSaved) {
    const select = document.getElementById("remind-zone");
    const emails = document.getElementById("remind-emails");
    if (!select || !emails) return;
    offerDeviceZone(select);
    let zone = select.value;
    select.addEventListener("change", () => {
      const chosen = select.value, before = zone;
      zone = chosen;
      save(pid, { time_zone: chosen },
        I18n.t("Saved. Your reminders now follow the clock in {zone}.", { zone: chosen.replace(/_/g, " ") }),
        () => { zone = before; select.value = before; }, onSaved);
    });
    emails.addEventListener("change", () => {
      const on = emails.checked;
      save(pid, { reminder_emails: on },
        on ? I18n.t("Saved. You will get your reminders by e-mail.") : I18n.t("Saved. You will get no reminder e-mails."),
        () => { emails.checked = !on; }, onSaved);
    });
  }

  return { init, deviceZone };
})();
