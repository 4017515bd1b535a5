/* The patient page's progress report form: the period (first and last day, the last 4 weeks unless changed) and the
   paper, checked here with the server's rule (both days given, the first on or before the last, at most 3 years:
   backend.records.report.Period.asked), then the PDF asked for and handed to the browser's downloads. A bad period
   is said next to the form and its field is marked; the server's own refusal is said the same way, never a JSON
   file saved in place of the PDF. Without this script the form still asks the server for the PDF. */
"use strict";
(() => {
  const { kindMessage, fileName, saveDownload, fmtDate, DAY } = Coach;
  const form = document.getElementById("report-form");
  if (!form) return;
  const $ = (id) => document.getElementById(id);
  const from = $("report-from"), to = $("report-to"), err = $("report-err"), state = $("report-state");
  const MAX_DAYS = 3 * 366;  // Period.asked: the last day at most this many days after the first
  const day = (iso) => fmtDate(iso + "T00:00:00Z", { day: "numeric", month: "long", year: "numeric", timeZone: "UTC" });

  function clear() {
    err.hidden = true;
    err.textContent = "";
    for (const box of [from, to]) box.removeAttribute("aria-invalid");
  }
  function refuse(text, boxes) {
    state.hidden = true;
    err.textContent = text;
    err.hidden = false;
    for (const box of boxes) box.setAttribute("aria-invalid", "true");
    boxes[0].focus();
  }
  function say(kind, text) { state.className = `small ${kind}`; state.textContent = text; state.hidden = false; }

  /** Returns what is wrong with the period in words, with the fields to mark, or null when the server accepts it. */
  function problem(start, end) {
    if (!start && !end) return [I18n.t("Choose the first and the last day of the report: the period is empty."), [from, to]];
    if (!start) return [I18n.t("Choose the first day of the report (a whole date)."), [from]];
    if (!end) return [I18n.t("Choose the last day of the report (a whole date)."), [to]];
    if (start > end) {
      return [I18n.t("The first day ({start}) is after the last day ({end}): choose a first day on or before the last day.",
        { start: day(start), end: day(end) }), [from, to]];
    }
    if ((Date.parse(end) - Date.parse(start)) / DAY > MAX_DAYS) {
      return [I18n.t("A report covers at most 3 years: choose a later first day or an earlier last day."), [from, to]];
    }
    return null;
  }

  for (const box of [from, to]) box.addEventListener("input", clear);
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    clear();
    const start = from.value, end = to.value;
    const wrong = problem(start, end);
    if (wrong) { refuse(...wrong); return; }
    const button = $("report-download");
    const query = new URLSearchParams({ from: start, to: end, paper: $("report-paper").value });
    button.disabled = true;
    say("muted", I18n.t("Making the report from {start} to {end}…", { start: day(start), end: day(end) }));
    let resp;
    try {
      resp = await fetch(`${form.action}?${query}`, { credentials: "same-origin", headers: { Accept: "application/pdf" } });
    } catch (e) {
      button.disabled = false;
      say("alert", I18n.t("The report could not be downloaded.") + " " + kindMessage({ status: 0 }));
      return;
    }
    button.disabled = false;
    if (!resp.ok) {
      const data = await resp.json().catch(() => null);
      if (resp.status === 422 && data && data.detail) {  // the server refused the period: said as a bad period
        refuse(I18n.t("The report cannot be made for this period: {reason}", { reason: data.detail }), [from, to]);
        return;
      }
      const detail = (data && data.detail) || resp.statusText;
      say("alert", I18n.t("The report could not be downloaded.") + " " + kindMessage({ status: resp.status, detail }));
      return;
    }
    const name = fileName(resp.headers.get("Content-Disposition"), "progress-report.pdf");
    saveDownload(await resp.blob(), name);
    say("note", I18n.t("The report from {start} to {end} is ready: {name} was handed to the browser's downloads.",
      { start: day(start), end: day(end), name }));
  });
})();
