/* Login page: the API's cookie login, then the start page of the user's role (or ?next=). */
"use strict";
(() => {
  const form = document.getElementById("login-form");
  const box = document.getElementById("login-error");
  const button = document.getElementById("login-submit");

  /** Returns ?next= when it is a path of this app on this origin (checked after URL parsing), else null. */
  function safeNext() {
    const next = new URLSearchParams(location.search).get("next");
    if (!next || !next.startsWith("/") || /[\\\u0000-\u0020]/.test(next)) return null;
    const target = new URL(next, location.origin);
    if (target.origin !== location.origin || !(target.pathname + "/").startsWith(Coach.root + "/")) return null;
    return target.pathname + target.search;
  }
  function say(text) { box.textContent = text; box.hidden = false; }
  if (new URLSearchParams(location.search).get("expired") === "1") {
    say(I18n.t("Your sign-in expired. Please sign in again: you will be taken back to where you were, with what you typed."));
  }

  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    box.hidden = true;
    const email = form.email.value.trim(), password = form.password.value;
    if (!email || !password) { say(I18n.t("Please fill in both your e-mail address and your password.")); return; }
    button.disabled = true; button.textContent = I18n.t("Signing in…");
    try {
      const out = await Coach.api("/auth/login", { method: "POST", body: { email, password }, redirect401: false, withCsrf: false });
      sessionStorage.setItem("coach_csrf", out.csrf_token);
      const home = Coach.url(out.user.role === "patient" ? "/patient" : "/therapist");
      location.assign(safeNext() || home);
    } catch (err) {
      if (err.status === 401) say(I18n.t("The e-mail address or the password is not right. Please try again."));
      else if (err.status === 429) say(I18n.t("Too many tries. Please wait a few minutes, then try again."));
      else say(Coach.kindMessage(err));
      form.password.value = "";
      form.password.focus();
    } finally {
      button.disabled = false; button.textContent = I18n.t("Sign in");
    }
  });
})();
