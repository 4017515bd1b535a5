/* Whether this page still hears the server: the live event stream sends an event at least every 2 s (a "ping" when
 * nothing else happens, backend/events/router.py PING_S); when the stream fails or stays silent for SILENT_MS the
 * server's health check is asked, and if it does not answer the connection is "lost" (at most SILENT_MS + 0.5 s +
 * PROBE_MS = 5 s after the last event) and it is asked again every PROBE_MS; once it answers the stream is reopened,
 * and its first event makes the connection "ok" again.
 * Listeners (Connection.listen) hear each change; the banner (#conn-banner) says it in plain words. */
"use strict";
const Connection = (() => {
  const SILENT_MS = 3000;  // no event for this long (pings come every 2 s): is the server still there?
  const PROBE_MS = 1500;  // the longest wait for the health check; while lost, how often it is asked again
  const STALE_MS = 8000;  // a stream silent this long while the server answers is reopened
  const TEXT = {
    lost: I18n.t("This page has lost its connection to the server. Please check that your internet is working. You do not need to do anything else: the page reconnects by itself."),
    back: I18n.t("The connection is back."),
  };
  let state = "connecting", last = Date.now(), probing = false, stream = null;  // last: when an event came
  const listeners = [];

  function set(next) {
    if (next === state) return;
    const was = state;
    state = next;
    banner(was);
    for (const f of listeners) { try { f(state, was); } catch (err) { console.error(err); } }
  }

  function banner(was) {
    const box = document.getElementById("conn-banner");
    if (!box) return;
    if (state === "lost") { box.textContent = TEXT.lost; box.dataset.state = "lost"; box.hidden = false; uncover(box); }
    else if (was === "lost") {
      box.textContent = TEXT.back; box.dataset.state = "ok";
      setTimeout(() => { if (state === "ok") box.hidden = true; }, 4000);
    }
  }

  /** Scrolls a live set that the banner (sticky at the window's top) covers to just below it: the set's title and
   * count stay readable while the connection is lost. */
  function uncover(box) {
    const live = document.getElementById("live");
    if (!live || live.hidden) return;
    const gap = live.getBoundingClientRect().top - box.getBoundingClientRect().bottom;
    if (gap < 0) window.scrollBy({ top: gap - 8, behavior: "instant" });
  }

  /** Called on every event of the stream: the server is there. */
  function heard() { last = Date.now(); if (state !== "ok") set("ok"); }

  /** Returns whether the server's health check answers 200 within PROBE_MS. */
  async function reachable() {
    try {
      const r = await fetch(Coach.url("/healthz"), { cache: "no-store", signal: AbortSignal.timeout(PROBE_MS) });
      return r.ok;
    } catch (err) { return false; }
  }

  /** Asks the server until it answers (lost meanwhile), then reopens the stream. */
  async function probe() {
    if (probing) return;
    probing = true;
    try {
      while (!(await reachable())) {
        set("lost");
        await new Promise((r) => setTimeout(r, PROBE_MS));
      }
      if (state === "lost") await Coach.api("/auth/csrf").catch(() => null);  // a sign-in that expired meanwhile: to the login
      if (stream && (state === "lost" || Date.now() - last > STALE_MS)) { last = Date.now(); stream.reconnect(); }
    } finally { probing = false; }
  }

  setInterval(() => {
    if (Date.now() - last > SILENT_MS) probe();  // a silent stream: the network may be gone without a word
  }, 500);

  /** Returns the handlers for Coach.onChange with the watchdog added (every event counts as heard). */
  function watch(handlers) {
    const out = { ping: heard, error: () => probe() };
    for (const [kind, f] of Object.entries(handlers)) out[kind] = (...args) => { heard(); return f(...args); };
    if (!handlers.open) out.open = heard;
    return out;
  }

  /** Keeps the stream Coach.onChange returned, to reopen it when the server is back. */
  function attach(s) { stream = s; }

  return { watch, attach, listen: (f) => listeners.push(f), get state() { return state; } };
})();
