/* Session page: the metrics of each analysis version, today's first, when a re-analysis replaced older ones, each
   with the pipeline that filtered its session file. */
"use strict";
(() => {
  const { api, el, fmtDateTime } = Coach;
  const sid = document.querySelector("main").dataset.sessionId;
  const cm = (v) => (v === null || v === undefined ? I18n.t("not measured") : I18n.t("{speed} cm/s", { speed: I18n.number(100 * v, 1) }));
  const num = (v, unit = "") => (v === null || v === undefined ? "—" : `${I18n.number(v)}${unit}`);
  // the pipeline that filtered the session file these metrics came from, and whether the server filtered it again
  const filteredBy = (v) => {
    const made = v.pipeline_version
      ? I18n.t("{pipeline}, settings {settings}", { pipeline: v.pipeline_version, settings: v.pipeline_settings || "—" })
      : I18n.t("not recorded");
    const again = v.refiltered ? " " + I18n.t("(filtered again by the server: {reason})", { reason: v.refiltered }) : "";
    const file = v.file_sha256 ? " · " + I18n.t("file {sha}", { sha: v.file_sha256.slice(0, 12) }) : "";
    const gone = v.file_sha256 && !v.file_kept ? " " + I18n.t("(file removed)") : "";
    return made + again + file + gone;
  };
  // what a re-filter changed, in words: the numbers before and after, why the server filtered the raw recording
  // again, and where the earlier numbers came from (versions: newest first; each re-filter against the one before)
  const whyChanged = (v, earlier) => {
    const what = I18n.t("Filtered again by the server with pipeline {pipeline}: range of motion {was} → {now}, repetitions {repsWas} → {repsNow}. Why: {reason}.",
      { pipeline: v.pipeline_version || "—", was: num(earlier.rom_deg, "°"), now: num(v.rom_deg, "°"),
        repsWas: num(earlier.repetitions), repsNow: num(v.repetitions), reason: v.refiltered });
    const source = earlier.pipeline_version
      ? I18n.t("The earlier numbers are the same raw recording filtered by pipeline {pipeline} (settings {settings}); the same raw recording filtered with the same settings gives the same numbers, so the difference is the pipeline's.",
        { pipeline: earlier.pipeline_version, settings: earlier.pipeline_settings || "—" })
      : I18n.t("The earlier file does not say which filter made its filtered recording (a file of another tool, or a test file): its numbers were not measured by this pipeline. The new numbers are what this pipeline measures from the same raw recording.");
    return el("p", {}, `${what} ${source}`);
  };
  api(`/sessions/${sid}/metric-versions`).then((versions) => {
    if (versions.length < 2) return;  // never re-analysed: nothing changed
    document.querySelector("#versions tbody").replaceChildren(...versions.map((v) => el("tr", {},
      el("td", {}, v.current ? I18n.t("{version} (today's)", { version: v.analysis_version }) : v.analysis_version),
      el("td", {}, num(v.repetitions)), el("td", {}, num(v.rom_deg, "°")), el("td", {}, cm(v.balance_sway_m_s)),
      el("td", {}, filteredBy(v)), el("td", {}, v.replaced_at ? fmtDateTime(v.replaced_at) : "—"))));
    document.getElementById("versions-why").replaceChildren(...versions.slice(0, -1)
      .map((v, i) => (v.refiltered ? whyChanged(v, versions[i + 1]) : null)).filter(Boolean));
    document.getElementById("versions-card").hidden = false;
  }).catch(() => {});  // the rest of the page stands without it
})();
