/* The session page's downloads (CSV, TRC, BVH, FHIR): a long recording's file is prepared once by a worker, so the
   server may answer 202 "being prepared" (with Retry-After) instead of the file. The page asks for the file itself,
   says in words that it is being prepared and asks again until the file comes, then hands it to the browser's
   downloads; a failure is said, never a JSON file saved in place of the download. */
"use strict";
(() => {
  const { kindMessage, fileName, saveDownload } = Coach;
  const nav = document.getElementById("downloads");
  const stateBox = document.getElementById("download-state");
  if (!nav || !stateBox) return;
  const MIN_WAIT_MS = 1500;
  const busy = new Set();  // links whose file is being asked for

  function say(kind, text) { stateBox.className = kind; stateBox.textContent = text; stateBox.hidden = false; }

  /** Asks for one link's file; while it is prepared, says so and asks again after the server's Retry-After. */
  async function fetchFile(link, label, waiting) {
    let resp;
    try {
      resp = await fetch(link.href, { credentials: "same-origin", headers: { Accept: "*/*" } });
    } catch (e) {
      if (waiting) {  // lost while waiting: say so, ask again
        say("alert", I18n.t("The server could not be asked whether the {file} file is ready; trying again.", { file: label }));
        setTimeout(() => fetchFile(link, label, true), MIN_WAIT_MS * 2);
        return;
      }
      say("alert", I18n.t("The {file} file could not be downloaded.", { file: label }) + " " + kindMessage({ status: 0 }));
      busy.delete(link);
      return;
    }
    if (resp.status === 202) {
      const d = await resp.json().catch(() => ({ state: "preparing", detail: "" }));
      if (d.state === "failed") {
        say("alert", I18n.t("The {file} file could not be prepared.", { file: label }) + " " + d.detail);
        busy.delete(link);
        return;
      }
      say("note", I18n.t("The {file} file is being prepared; it will download by itself when it is ready.", { file: label }) + " " + d.detail);
      const wait = Math.max(MIN_WAIT_MS, 1000 * (Number(resp.headers.get("Retry-After")) || 0));
      setTimeout(() => fetchFile(link, label, true), wait);
      return;
    }
    busy.delete(link);
    if (!resp.ok) {
      const data = await resp.json().catch(() => null);
      const err = { status: resp.status, error: data && data.error, detail: (data && data.detail) || resp.statusText };
      if ([400, 409, 410].includes(resp.status) && data && data.detail) {  // the file cannot be made: the server says why
        say("alert", I18n.t("The {file} file cannot be made: {reason}", { file: label, reason: data.detail }));
      } else {
        say("alert", I18n.t("The {file} file could not be downloaded.", { file: label }) + " " + kindMessage(err));
      }
      return;
    }
    const name = fileName(resp.headers.get("Content-Disposition"), label);
    saveDownload(await resp.blob(), name);
    say("note", I18n.t("The {file} file is ready: {name} was handed to the browser's downloads.", { file: label, name }));
  }

  nav.addEventListener("click", (event) => {
    const link = event.target.closest("a[href*='/export?format=']");
    if (!link) return;
    event.preventDefault();
    if (busy.has(link)) return;
    busy.add(link);
    const label = link.textContent.trim();  // the format as the page names it: "Motion (BVH)"
    say("note", I18n.t("Asking for the {file} file…", { file: label }));
    fetchFile(link, label, false);
  });
})();
