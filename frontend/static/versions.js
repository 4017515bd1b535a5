/* Session page: the metrics of each analysis version, today's first, when a re-analysis replaced older ones. */
"use strict";
(() => {
  const { api, el, fmtDateTime } = Coach;
  const sid = document.querySelector("main").dataset.sessionId;
  const cm = (v) => (v === null || v === undefined ? I18n.t("not measured") : I18n.t("{speed} cm/s", { speed: I18n.number(100 * v, 1) }));
  const num = (v, unit = "") => (v === null || v === undefined ? "—" : `${I18n.number(v)}${unit}`);
  api(`/sessions/${sid}/metric-versions`).then((versions) => {
    if (versions.length < 2) return;  // never re-analysed: nothing changed
    document.querySelector("#versions tbody").replaceChildren(...versions.map((v) => el("tr", {},
      el("td", {}, v.current ? I18n.t("{version} (today's)", { version: v.analysis_version }) : v.analysis_version),
      el("td", {}, num(v.repetitions)), el("td", {}, num(v.rom_deg, "°")), el("td", {}, cm(v.balance_sway_m_s)),
      el("td", {}, v.replaced_at ? fmtDateTime(v.replaced_at) : "—"))));
    document.getElementById("versions-card").hidden = false;
  }).catch(() => {});  // the rest of the page stands without it
})();
