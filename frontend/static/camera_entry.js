/* The patient screen's "Start with this computer's camera" next to each exercise: a link to the camera page, shown
 * only when the browser reports a camera (before any permission is asked, the list holds its kind only). */
"use strict";
const CameraEntry = (() => {
  const { el } = Coach;
  const LABEL = I18n.t("Start with this computer's camera");
  let hasCamera = null;

  async function check() {
    if (hasCamera !== null) return hasCamera;
    try {
      const devices = navigator.mediaDevices && navigator.mediaDevices.enumerateDevices ? await navigator.mediaDevices.enumerateDevices() : [];
      hasCamera = devices.some((d) => d.kind === "videoinput");
    } catch (err) { hasCamera = false; }
    return hasCamera;
  }

  /** Returns the (hidden) link of one plan item (name: the exercise's, label: "set 2 of 3" or "extra set" in the
   *  page's language); reveal() shows the links when there is a camera. */
  function link(item, name, label) {
    return el("a", { class: "btn btn-big btn-quiet cam-start", hidden: true, "aria-label": I18n.t("{start}: {exercise}, {set}", { start: LABEL, exercise: name, set: label }),
      href: Coach.url(`/patient/camera?item=${encodeURIComponent(item.id)}`) }, LABEL);
  }

  /** Shows the links when there is a camera; returns whether there is one. */
  async function reveal() {
    const yes = await check();
    for (const a of document.querySelectorAll("a.cam-start")) a.hidden = !yes;
    return yes;
  }

  /** Whether the browser has reported a camera (false until it has answered). */
  return { link, reveal, LABEL, get available() { return hasCamera === true; } };
})();
