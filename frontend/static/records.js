/* The patient's data on the patient page (admins): erasure, confirmed twice (a checkbox, then the e-mail typed). */
"use strict";
(() => {
  const { api, url, showError } = Coach;
  const section = document.getElementById("records");
  if (!section) return;
  const pid = document.querySelector("main").dataset.patientId;
  const $ = (id) => document.getElementById(id);
  let email = null;

  function show(step) {
    $("erase-start").hidden = step !== 0;
    $("erase-step1").hidden = step !== 1;
    $("erase-step2").hidden = step !== 2;
  }

  $("erase-start").addEventListener("click", async () => {
    try {
      email = (await api(`/patients/${pid}`)).email;
    } catch (err) { showError(err); return; }
    $("erase-understand").checked = false;
    $("erase-continue").disabled = true;
    show(1);
    $("erase-understand").focus();
  });
  $("erase-understand").addEventListener("change", (e) => { $("erase-continue").disabled = !e.target.checked; });
  $("erase-continue").addEventListener("click", () => { $("erase-email").value = ""; show(2); $("erase-email").focus(); });
  for (const id of ["erase-cancel1", "erase-cancel2"]) $(id).addEventListener("click", () => { show(0); $("erase-start").focus(); });
  $("erase-email").addEventListener("input", (e) => {
    $("erase-confirm").disabled = e.target.value.trim().toLowerCase() !== (email || "").toLowerCase();
  });
  $("erase-step2").addEventListener("submit", async (e) => {
    e.preventDefault();
    const msg = $("erase-msg");
    $("erase-confirm").disabled = true;
    try {
      const out = await api(`/patients/${pid}/erasure`, { method: "POST", body: { confirm_email: $("erase-email").value.trim() } });
      const rows = Object.values(out.rows).reduce((a, b) => a + b, 0);
      show(-1);
      msg.className = "note";
      msg.replaceChildren(I18n.t("The patient was erased: {rows} records and {files} stored files deleted.",
        { rows, files: out.objects }) + " ",
        Object.assign(document.createElement("a"), { href: url("/therapist"), textContent: I18n.t("Back to all patients") }));
      msg.hidden = false;
      msg.focus();
    } catch (err) {
      msg.className = "alert";
      msg.textContent = I18n.t("Nothing was erased: {reason}", { reason: err.detail || err.message });
      msg.hidden = false;
      $("erase-confirm").disabled = false;
    }
  });
})();
