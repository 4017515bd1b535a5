/* Every sentence the camera page shows or speaks, in one place, in the page's language: the messages come from the
 * gettext catalogues (backend/i18n) through I18n.t / I18n.nt (i18n.js, loaded before this file). */
"use strict";
const CameraText = Object.freeze({
  loading: I18n.t("Getting the camera ready…"),
  loadingModel: I18n.t("Loading the movement tracker… This can take a few seconds the first time."),
  noCameraApi: I18n.t("This browser cannot use a camera. Please try a current version of Chrome, Edge, Firefox or Safari."),
  noCamera: I18n.t("We could not find a camera on this computer. If it has one, check that it is plugged in and not covered, then press Try again."),
  denied: I18n.t('The browser did not allow this page to use the camera. Click the camera symbol next to the address bar, choose "Allow", then press Try again.'),
  busy: I18n.t("The camera is being used by another program. Please close that program (for example a video call), then press Try again."),
  cameraFailed: I18n.t("The camera could not be started. Please check that it is plugged in, then press Try again."),
  trackerFailed: I18n.t("The movement tracker could not start on this computer. Please try again, or use another computer."),
  /** The problem card's heading: the camera did not start, it stopped mid-set, or anything else went wrong. */
  cannotStart: I18n.t("The camera cannot start"),
  cameraStopped: I18n.t("The camera stopped"),
  wentWrong: I18n.t("Something went wrong"),
  unplugged: I18n.t("The camera was disconnected. Plug it back in and press Try again. What you did so far is kept."),
  notInPlan: I18n.t("This exercise is not in your plan right now. Please go back to your exercises."),
  readFirst: I18n.t("Please read this first."),
  saveWhatIDid: I18n.t("Save what I did"),
  // placement check
  nobody: I18n.t("We cannot see you. Please step in front of the camera."),
  twoPeople: I18n.t("We can see more than one person. Please make sure only you are in the picture."),
  wholeBody: I18n.t("Step back until your whole body is in the picture, from head to feet."),
  upperBody: I18n.t("Step back until your head, arms and hips are in the picture."),
  tooClose: I18n.t("Step back a little."),
  tooFar: I18n.t("Come a little closer to the camera."),
  sideView: I18n.t("Please turn sideways to the camera, so it sees you from the side."),
  frontView: I18n.t("Please face the camera."),
  dark: I18n.t("The room is too dark. Please turn on a light or open the curtains."),
  offCentre: I18n.t("Move to the middle of the picture."),
  placementOk: I18n.t("Good! Stay like this — we start counting now."),
  placementHold: I18n.t("Good! Hold still for a moment…"),
  // during the set
  counting: I18n.t("Counting. Do your exercise at your own pace."),
  leftFrame: I18n.t("You left the picture. Please come back in view — the set goes on when you are back."),
  keptPatient: I18n.t("Someone else is in the picture. We keep following you; please ask them to step out."),
  hidden: I18n.t("The set paused because this page was hidden. Come back to this page to go on."),
  resumed: I18n.t("Welcome back — the set goes on."),
  slow: I18n.t("This computer is slow, so counting may be less exact."),
  lighter: I18n.t("This computer is slow, so we switched to a lighter movement tracker."),
  offline: I18n.t("The connection to the server is lost. Keep going: your movements are kept on this computer and sent when the connection is back."),
  online: I18n.t("The connection is back. Everything is sent."),
  serverTrouble: I18n.t("Something went wrong on our side. Keep going: your movements are kept on this computer and we keep trying to send them."),
  saving: I18n.t("Saving your set…"),
  savingOffline: I18n.t("Your set is kept on this computer. It will be saved as soon as the connection is back."),
  tooShort: I18n.t("The set was too short to save. Please try again and do at least one repetition."),
  notSaved: I18n.t("This set could not be saved. Please try again; if it happens again, please tell your therapist."),
  saveFailed: I18n.t("Your set could not be saved. It is kept on this computer; please reload the page to try again."),
  /** The interrupted set: seconds kept so far and the exercise's name (lower case in English sentences only). */
  resumeText: (n, name) => I18n.t("We kept {seconds} seconds of your set ({exercise}). You can go on with the set, or save what you did.",
    { seconds: n, exercise: I18n.locale === "en" ? name.toLowerCase() : name }),
  result: (reps, target) => (reps === null || reps === undefined ? I18n.t("Your set is saved. We could not count the repetitions this time.")
    : reps >= target ? I18n.nt("Saved: all {n} repetition — well done!", "Saved: all {n} repetitions — well done!", reps)
      : I18n.t("Saved: {done} of {goal} repetitions. Good effort!", { done: reps, goal: target })),
  resultRom: (deg) => I18n.t("You moved through {rom} degrees.", { rom: Math.round(deg) }),
  /** The saved count differs from the last one shown during the set (counted again over the whole set): said. */
  recounted: (shown, saved) => I18n.t("While you exercised we counted {shown}. Counted again over the whole set, it is {saved}.",
    { shown, saved }),
  ended: { target: I18n.t("You reached your goal."), stop: I18n.t("You stopped the set."),
    still: I18n.t("The set ended because you did not move for a while."), limit: I18n.t("The set reached its time limit."),
    error: I18n.t("The set stopped because of a problem.") },
  /** The result's second line: why the set ended, the recount when the saved count differs from the last one shown,
   *  the range moved (degrees or null). A set the live count ended at its target "reached your goal" only when the
   *  saved count (saved: null when it could not be counted) reaches the target too; otherwise the recount says why. */
  resultMore(reason, shown, saved, target, romDeg) {
    const goalMissed = reason === "target" && (saved === null || saved < target);
    const recount = saved !== null && saved !== shown ? this.recounted(shown, saved) : "";
    const rom = romDeg ? this.resultRom(romDeg) : "";
    return [goalMissed ? "" : this.ended[reason] || "", recount, rom].filter(Boolean).join(" ");
  },
  /** The big count's small part ("of 10") and the count said to screen readers ("3 of 10"). */
  countOf: (target) => " " + I18n.t("of {goal}", { goal: target }),
  countSpoken: (n, target) => I18n.t("{done} of {goal}", { done: n, goal: target }),
  /** A hint of the server's live count (kinect_agent/analysis/live.py HINT_*, marked in live.js) in this language. */
  hint: (text) => I18n.t(text),
  startButton: I18n.t("Start with this computer's camera"),
  viewSide: I18n.t("Stand sideways to the camera."),
  viewFront: I18n.t("Face the camera."),
  /** The placement's heading line: the exercise's name and the view it needs. */
  nameAndView: (name, view) => I18n.t("{exercise}: {view}", { exercise: name, view }),
});
