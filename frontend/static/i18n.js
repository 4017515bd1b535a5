/* The page scripts' messages in the page's language, from the same gettext catalogues as the server's (backend/i18n):
 * the page carries them as JSON (<script type="application/json" id="i18n-messages">, backend.i18n.js_messages).
 *   I18n.t("Hello, {name}!", { name })              -> the translation, placeholders filled
 *   I18n.nt("{n} set", "{n} sets", n, { ... })      -> the singular or plural form for n ({n} is n)
 *   I18n.date(iso, options), I18n.number(x, digits)  -> dates and numbers the way the page's language writes them
 *   I18n.percent(fraction)                           -> 0.85: "85%" / "85 %"
 *   I18n.N_("text")                                  -> marks a text that arrives from elsewhere (translated by I18n.t(text))
 * Mark every user-facing string with I18n.t / I18n.nt (python -m backend.i18n.catalogues extract finds them). */
"use strict";
const I18n = (() => {
  const node = document.getElementById("i18n-messages");
  const data = node ? JSON.parse(node.textContent) : { locale: "en", plural: "n != 1", messages: {} };
  const locale = data.locale || "en";
  const tag = locale === "en" ? "en-GB" : locale;  // the language tag for Intl (English pages write 27 November 2026)
  const pluralIndex = data.plural === "n > 1" ? (n) => (n > 1 ? 1 : 0) : (n) => (n !== 1 ? 1 : 0);
  const numbers = new Intl.NumberFormat(tag, { maximumFractionDigits: 1 });

  function show(value) { return typeof value === "number" ? numbers.format(value) : String(value); }
  function fill(text, params) {
    return params ? text.replace(/\{(\w+)\}/g, (all, key) => (key in params ? show(params[key]) : all)) : text;
  }
  /** Returns the translation of msgid with {name} placeholders filled from params. */
  function t(msgid, params) {
    const text = data.messages[msgid];
    return fill(typeof text === "string" && text ? text : msgid, params);
  }
  /** Returns the translation of the singular or plural form for n, with {n} and params filled. */
  function nt(singular, plural, n, params) {
    const forms = data.messages[singular + "\u0004" + plural];
    const i = pluralIndex(n);
    const text = Array.isArray(forms) && forms[i] ? forms[i] : (i === 0 ? singular : plural);
    return fill(text, { n, ...(params || {}) });
  }
  /** Returns a date in the page's language (options as Intl.DateTimeFormat's). */
  function date(iso, options) { return new Date(iso).toLocaleDateString(tag, options); }
  /** Returns a date and time in the page's language. */
  function dateTime(iso, options) { return new Date(iso).toLocaleString(tag, options); }
  /** Returns a number in the page's language, with at most `digits` decimals (0 unless given). */
  function number(x, digits = 0) { return new Intl.NumberFormat(tag, { maximumFractionDigits: digits }).format(x); }
  /** Returns a fraction as a whole percentage in the page's language (Babel's format_percent on the server). */
  function percent(fraction) { return new Intl.NumberFormat(tag, { style: "percent", maximumFractionDigits: 0 }).format(fraction); }

  /** The header's language select (patients): saves the choice for the patient, then shows the page in it. */
  document.addEventListener("DOMContentLoaded", () => {
    const select = document.getElementById("language");
    if (!select) return;
    select.addEventListener("change", async () => {
      select.disabled = true;
      try {
        await Coach.api(`/patients/${select.dataset.patientId}`, { method: "PATCH", body: { locale: select.value } });
        location.reload();
      } catch (err) { select.disabled = false; Coach.showError(err); }
    });
  });

  /** Marks a message for the catalogue without translating it here (a text that arrives from elsewhere, e.g. the
   *  home computer's hints, and is translated by I18n.t(text) where it is shown). */
  function N_(msgid) { return msgid; }

  return { locale, tag, t, nt, N_, date, dateTime, number, percent };
})();
