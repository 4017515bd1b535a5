/* Shared page code: API calls with the login cookie and CSRF header, kind error messages, small DOM helpers. */
"use strict";
const Coach = (() => {
  let csrf = null;
  // the path prefix of the app's URLs (from the server's COACH_PUBLIC_URL): "" or e.g. "/clinic"
  const root = (document.querySelector('meta[name="coach-root"]') || { content: "" }).content;
  /** Returns the URL of one of the app's paths ("/therapist" -> root + "/therapist"). */
  function url(path) { return root + path; }

  class ApiError extends Error {
    constructor(status, error, detail) { super(detail || error); this.status = status; this.error = error; this.detail = detail; }
  }

  const DRAFTS = "coach_drafts:";  // + the page's path: {textarea id: text} kept over a sign-in that expired
  /** Goes to the login page (back here after signing in); text typed into the page's text boxes is kept. */
  function toLogin() {
    const next = location.pathname + location.search;
    const drafts = Object.fromEntries([...document.querySelectorAll("textarea[id]")].filter((t) => t.value.trim())
      .map((t) => [t.id, t.value]));
    if (Object.keys(drafts).length) sessionStorage.setItem(DRAFTS + next, JSON.stringify(drafts));
    location.assign(url("/?expired=1&next=") + encodeURIComponent(next));
  }
  /** Puts back what was typed before the sign-in expired (toLogin); says so next to each text box. */
  function restoreDrafts() {
    const key = DRAFTS + location.pathname + location.search;
    const drafts = JSON.parse(sessionStorage.getItem(key) || "{}");
    sessionStorage.removeItem(key);
    for (const [id, text] of Object.entries(drafts)) {
      const box = document.getElementById(id);
      if (!box || box.value.trim()) continue;
      box.value = text;
      const note = el("p", { class: "note draft-kept", role: "status" },
        I18n.t("Your sign-in had expired. What you typed is kept here: please check it and send it again."));
      box.after(note);
      box.addEventListener("input", () => note.remove(), { once: true });
    }
  }

  async function csrfToken() {
    if (!csrf) csrf = sessionStorage.getItem("coach_csrf");
    if (!csrf) { csrf = (await api("/auth/csrf")).csrf_token; sessionStorage.setItem("coach_csrf", csrf); }
    return csrf;
  }

  /** Calls /api/v1 + path; returns the JSON body; throws ApiError with the API's {error, detail}. */
  async function api(path, { method = "GET", body, redirect401 = true, retried = false, withCsrf = true } = {}) {
    const headers = { Accept: "application/json", "Accept-Language": I18n.locale };  // errors in the page's language
    if (method !== "GET" && withCsrf) headers["X-CSRF-Token"] = await csrfToken();
    if (body !== undefined) headers["Content-Type"] = "application/json";
    let resp;
    try {
      resp = await fetch(url("/api/v1" + path), { method, headers, credentials: "same-origin",
        body: body === undefined ? undefined : JSON.stringify(body) });
    } catch (e) {
      throw new ApiError(0, "NetworkError", I18n.t("The server could not be reached."));
    }
    if (resp.status === 401 && redirect401) { sessionStorage.removeItem("coach_csrf"); toLogin(); throw new ApiError(401, "NotAuthenticated", I18n.t("Please sign in again.")); }
    if (resp.status === 403 && method !== "GET" && !retried) {
      const err = await resp.clone().json().catch(() => ({}));
      if (err.error === "CsrfFailed") { csrf = null; sessionStorage.removeItem("coach_csrf"); return api(path, { method, body, redirect401, retried: true }); }
    }
    if (resp.status === 204) return null;
    const data = await resp.json().catch(() => null);
    if (!resp.ok) {
      // a detail the server could not say in the page's language is left out of the page (kindMessage says enough)
      const said = I18n.locale === "en" || resp.headers.get("Content-Language") === I18n.locale;
      throw new ApiError(resp.status, (data && data.error) || "HTTPError", said ? (data && data.detail) || resp.statusText : "");
    }
    return data;
  }

  /** Returns a sentence for people: what went wrong and what to do, plus the server's own words. */
  function kindMessage(err) {
    const s = err && err.status;
    let head;
    if (s === 0) head = I18n.t("We cannot reach the server right now. Please check the internet connection and try again.");
    else if (s === 401) head = I18n.t("Your sign-in expired. Please sign in again.");
    else if (s === 403) head = I18n.t("Sorry, your account may not see or change this.");
    else if (s === 404) head = I18n.t("Sorry, we could not find this.");
    else if (s === 409) head = I18n.t("This was changed in the meantime. Please reload the page.");
    else if (s === 422) head = I18n.t("Some of the information is not right. Please check it and try again.");
    else if (s === 429) head = I18n.t("Too many tries. Please wait a few minutes and try again.");
    else if (s >= 500) head = I18n.t("Something went wrong on our side. Please try again in a moment.");
    else head = I18n.t("Something went wrong.");
    const detail = err && err.detail && s !== 0 ? ` (${err.detail})` : "";
    return head + detail;
  }

  function showError(err, where) {
    if (err && err.status === 401) return;
    console.error(err);
    const box = where || document.getElementById("error");
    if (!box) return;
    box.textContent = kindMessage(err);
    box.hidden = false;
  }

  /** el("p", {class: "x"}, "text", child) -> element (strings become text nodes, never HTML). */
  function el(tag, attrs, ...children) {
    const node = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (v === null || v === undefined || v === false) continue;
      if (k.startsWith("on")) node.addEventListener(k.slice(2), v); else node.setAttribute(k, v === true ? "" : v);
    }
    for (const c of children.flat()) if (c !== null && c !== undefined && c !== false) node.append(c instanceof Node ? c : String(c));
    return node;
  }

  const DAY = 86400000;
  function startOfDay(d) { const x = new Date(d); x.setHours(0, 0, 0, 0); return x; }
  function startOfWeekUTC(now = new Date()) {  // Monday 00:00 UTC, as the API counts weeks
    const d = new Date(Date.UTC(now.getUTCFullYear(), now.getUTCMonth(), now.getUTCDate()));
    d.setUTCDate(d.getUTCDate() - ((d.getUTCDay() + 6) % 7));
    return d;
  }
  function fmtDate(iso, opts) {
    return I18n.date(iso, opts || { weekday: "short", day: "numeric", month: "short", year: "numeric" });
  }
  function fmtDateTime(iso) {
    return I18n.dateTime(iso, { day: "numeric", month: "short", year: "numeric", hour: "2-digit", minute: "2-digit" });
  }
  function fmtTime(iso) { return new Date(iso).toLocaleTimeString(I18n.tag, { hour: "2-digit", minute: "2-digit" }); }
  function daysAgo(iso) { return Math.round((startOfDay(new Date()) - startOfDay(new Date(iso))) / DAY); }
  function plainDay(iso) {
    const n = daysAgo(iso);
    if (n === 0) return I18n.t("today");
    if (n === 1) return I18n.t("yesterday");
    return I18n.t("on {day}", { day: fmtDate(iso, { weekday: "long", day: "numeric", month: "long" }) });
  }
  function median(xs) {
    const s = xs.filter((x) => x !== null && x !== undefined && isFinite(x)).sort((a, b) => a - b);
    if (!s.length) return null;
    const m = s.length >> 1;
    return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2;
  }

  let exercisesPromise = null;
  /** Returns {slug: exercise} of the exercise library (cached). */
  function exercises() {
    exercisesPromise = exercisesPromise || api("/exercises?limit=200").then((p) => Object.fromEntries(p.items.map((e) => [e.slug, e])));
    return exercisesPromise;
  }
  function exerciseName(lib, slug) { return (lib[slug] && lib[slug].name) || (slug || "exercise").replace(/_/g, " "); }

  /** Returns the plan running today (start <= today <= end), newest first. */
  function runningPlan(plans) {
    const today = new Date().toISOString().slice(0, 10);
    return plans.find((p) => p.start_date <= today && (!p.end_date || p.end_date >= today)) || null;
  }

  /**
   * Calls reload() when the server says something changed about the patients this page shows (a new session,
   * changed advice, a changed plan, a reply to advice): server-sent events on this origin, behind the same login. Bursts of events
   * give one call; the browser reconnects by itself and the page reloads its data then too.
   * patientId: only that patient's events (null: every patient the signed-in user may see).
   */
  /** Opens the page's event stream: reload() after stored data changed (and after a reconnect, for events missed
   *  meanwhile); with `live` ({kind: handler(data)}, open: called on each connection), also the live loop's events. */
  function onChange(patientId, reload, live) {
    if (!window.EventSource) return null;
    const query = new URLSearchParams();
    if (patientId) query.set("patient_id", patientId);
    if (live) query.set("live", "true");
    let source = null, timer = null, opened = false, again = null;
    const soon = () => { clearTimeout(timer); timer = setTimeout(reload, 300); };
    function connect() {
      source = new EventSource(url("/api/v1/events" + (query.toString() ? "?" + query : "")));
      for (const kind of ["session.stored", "suggestion.changed", "plan.changed", "reply.changed"]) source.addEventListener(kind, soon);
      for (const [kind, handler] of Object.entries(live || {})) {
        if (kind === "open" || kind === "error") continue;  // called on every (re)connection and failure, below
        source.addEventListener(kind, (e) => { try { handler(JSON.parse(e.data).data || {}, e); } catch (err) { console.error(err); } });
      }
      source.addEventListener("open", () => { if (opened) soon(); opened = true; if (live && live.open) live.open(); });
      source.addEventListener("error", () => {
        if (live && live.error) live.error(source.readyState === EventSource.CLOSED);
        // an answer other than a stream (a proxy's 502 while the server restarts, a 401) makes the browser give up:
        // the page does not
        if (source.readyState === EventSource.CLOSED && !again) again = setTimeout(() => { again = null; connect(); }, 3000);
      });
    }
    connect();
    window.addEventListener("pagehide", () => { clearTimeout(again); source.close(); });
    return { close: () => { clearTimeout(again); source.close(); }, reconnect: () => { clearTimeout(again); source.close(); connect(); } };
  }

  /** Returns the file name of a Content-Disposition header ('attachment; filename="x.pdf"'), or fallback. */
  function fileName(disposition, fallback) {
    const m = /filename="?([^";]+)"?/.exec(disposition || "");
    return m ? m[1] : fallback;
  }
  /** Hands bytes to the browser's downloads under name. */
  function saveDownload(blob, name) {
    const a = document.createElement("a");
    a.href = URL.createObjectURL(blob);
    a.download = name;
    a.hidden = true;
    document.body.append(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 60_000);
  }

  async function logout() {
    try { await api("/auth/logout", { method: "POST", redirect401: false }); } catch (e) { /* already signed out */ }
    sessionStorage.removeItem("coach_csrf");
    location.assign(url("/"));
  }
  document.addEventListener("DOMContentLoaded", () => {
    restoreDrafts();
    const b = document.getElementById("logout");
    if (b) b.addEventListener("click", logout);
  });

  return { root, url, api, onChange, ApiError, kindMessage, showError, el, fmtDate, fmtDateTime, fmtTime, plainDay, daysAgo, startOfWeekUTC, median,
           exercises, exerciseName, runningPlan, toLogin, fileName, saveDownload, DAY };
})();
