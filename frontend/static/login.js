/* Login page: the API's cookie login, then the start page of the user's role (or ?next=). */
"use strict";
(() => {
  const form = document.getElementById("login-form");
  const box = document.getElementById("login-error");
  const button = document.getElementById("login-submit");

  function safeNext() {
    const next = new URLSearchParams(location.search).get("next");
    return next && next.startsWith("/") && !next.startsWith("//") ? next : null;
  }
  function say(text) { box.textContent = text; box.hidden = false; }

  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    box.hidden = true;
    const email = form.email.value.trim(), password = form.password.value;
    if (!email || !password) { say("Please fill in both your e-mail address and your password."); return; }
    button.disabled = true; button.textContent = "Signing in…";
    try {
      const out = await Coach.api("/auth/login", { method: "POST", body: { email, password }, redirect401: false, withCsrf: false });
      sessionStorage.setItem("coach_csrf", out.csrf_token);
      const home = out.user.role === "patient" ? "/patient" : "/therapist";
      location.assign(safeNext() || home);
    } catch (err) {
      if (err.status === 401) say("The e-mail address or the password is not right. Please try again.");
      else if (err.status === 429) say("Too many tries. Please wait a few minutes, then try again.");
      else say(Coach.kindMessage(err));
      form.password.value = "";
      form.password.focus();
    } finally {
      button.disabled = false; button.textContent = "Sign in";
    }
  });
})();
