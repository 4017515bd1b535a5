/* All of a patient's data as one zip (the patient's page, and an admin's page of the patient): a worker makes the
   archive, never the request. The page asks the server where it is, asks for one with the button, says how far the
   worker is (sessions written) until it is ready, then shows the download link; a failure or a lost server is said
   in words and recovered from, never silent. The server's URLs are relative to the app's own origin. */
"use strict";
(() => {
  const { api, kindMessage } = Coach;
  const box = document.getElementById("archive");
  if (!box) return;
  const pid = box.dataset.patientId;
  const ask = document.getElementById("archive-ask");
  const link = document.getElementById("archive-link");
  const stateBox = document.getElementById("archive-state");
  const POLL_MS = 2000;
  let timer = null;

  function say(kind, text) { stateBox.className = kind; stateBox.textContent = text; stateBox.hidden = !text; }

  function size(bytes) {
    return bytes >= 1048576 ? I18n.t("{mb} MB", { mb: I18n.number(bytes / 1048576, 1) })
      : I18n.t("{kb} kB", { kb: I18n.number(Math.max(1, bytes / 1024)) });
  }

  function made(out) {
    let text = I18n.nt("Made {date}: {n} session, {size}.", "Made {date}: {n} sessions, {size}.", out.sessions,
      { date: I18n.dateTime(out.made_at), size: size(out.size) });
    if (out.incomplete) {
      text += " " + I18n.nt("{n} session lacks a file or an export: the README inside says why.",
        "{n} sessions lack a file or an export: the README inside says why.", out.incomplete);
    }
    return text;
  }

  /** Shows one state of the archive (the server's ArchiveOut) and asks again while a worker makes it. */
  function show(out) {
    clearTimeout(timer);
    const kept = out.download_url !== null;
    link.hidden = !kept;
    if (kept) link.href = out.download_url;
    ask.hidden = out.state === "preparing" || (out.state === "ready" && out.current);
    ask.disabled = false;
    ask.textContent = out.state === "failed" ? ask.dataset.retry : kept ? ask.dataset.again : ask.dataset.first;
    if (out.state === "preparing") {
      let text = I18n.t("The archive is being made; the download link appears here when it is ready.") + " " + out.detail;
      if (out.progress) text += " " + I18n.t("{done} of {total} sessions written.", out.progress);
      say("note", text);
      timer = setTimeout(poll, POLL_MS);
    } else if (out.state === "failed") {
      say("alert", out.detail);
    } else if (out.state === "ready") {
      say("note", made(out) + (out.current ? "" : " " + I18n.t("It does not hold the newest data: make a new one to include it.")));
    } else {
      say("", "");
    }
  }

  async function poll() {
    try {
      show(await api(`/patients/${pid}/archive/status`));
    } catch (err) {
      if (err.status === 401) return;
      say("alert", I18n.t("The server could not be asked whether the archive is ready; trying again.") + " " + kindMessage(err));
      timer = setTimeout(poll, POLL_MS * 2);
    }
  }

  ask.addEventListener("click", async () => {
    ask.disabled = true;
    say("note", I18n.t("Asking for the archive…"));
    try {
      show(await api(`/patients/${pid}/archive`, { method: "POST" }));
    } catch (err) {
      ask.disabled = false;
      say("alert", I18n.t("The archive could not be asked for.") + " " + kindMessage(err));
    }
  });
  poll();
})();
