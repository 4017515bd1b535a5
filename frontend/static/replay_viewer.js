/* Inside viser's player (/replay/viewer/, frontend/replay_viewer.py): viser's own words in the reader's language.
 * viser 1.1.1's client (pinned) writes its playback bar, its scene tree panel (title, node names) and its browser
 * notices in English from a compressed bundle; React renders each as a text node or an attribute. This script
 * watches the player's DOM and, where a text or an aria-label/title/placeholder is exactly one of VISER_WORDS (or a
 * scene tree row's name is one of SCENE_NAMES), writes it in the page's language (changing the node's text in place,
 * so React keeps its node), and names the controls viser leaves without a name (the play/pause button, the time
 * field, the speed choice). What stays English: docs/languages.md. */
"use strict";
(() => {
  // viser's words as its sources write them (FilePlayback.tsx, PlaybackScenePanel.tsx, BrowserWarning.tsx)
  const VISER_WORDS = new Set([
    I18n.N_("Playback speed"), I18n.N_("Scene tree"), I18n.N_("Show scene tree"), I18n.N_("Hide scene tree"),
    I18n.N_("Toggle visibility override"), I18n.N_("Clear visibility override"),
    I18n.N_("Software WebGL rendering detected"),
    I18n.N_("WebGL is running in software mode, not on your GPU. Performance may be degraded. If this is unexpected, check that hardware acceleration is enabled in your browser settings."),
    I18n.N_("WebGL unavailable"),
    I18n.N_("WebGL is unavailable. This may be caused by hardware acceleration being disabled — check your browser settings."),
    I18n.N_("Could not detect browser version"),
    I18n.N_("Your browser version could not be detected. It may not be supported."),
  ]);
  // the replay's scene nodes (backend/replay/scene.py) as viser's scene tree panel names them (the last part of each
  // path, a text node of its own in the node's row, [data-scene-node]), and the words the page says for each
  const SCENE_NAMES = new Map([["floor", I18n.N_("Floor")], ["raw", I18n.N_("Raw skeleton")],
    ["filtered", I18n.N_("Filtered skeleton")], ["bones", I18n.N_("Bones")], ["joints", I18n.N_("Joints")],
    ["outliers", I18n.N_("Tracking errors")]]);
  const SCENE_PATH = new RegExp(`^(/(${[...SCENE_NAMES.keys()].join("|")}))+$`);
  const ATTRIBUTES = ["aria-label", "title", "placeholder"];

  function translateText(node) {
    const text = node.nodeValue;
    let said = null;
    if (VISER_WORDS.has(text)) said = I18n.t(text);
    else if (SCENE_NAMES.has(text) && node.parentElement && node.parentElement.closest("[data-scene-node]")) {
      said = I18n.t(SCENE_NAMES.get(text));
    } else if (SCENE_PATH.test(text)) {  // the label viser shows in the scene while a row is hovered: "/raw/bones"
      said = text.split("/").map((part) => (part ? I18n.t(SCENE_NAMES.get(part)) : part)).join("/");
    }
    if (said !== null && said !== text) node.nodeValue = said;
  }
  function translateAttributes(el) {
    for (const name of ATTRIBUTES) {
      const value = el.getAttribute(name);
      if (value === null || !VISER_WORDS.has(value)) continue;
      const said = I18n.t(value);
      if (said !== value) el.setAttribute(name, said);  // setting it unchanged would call the observer again, forever
    }
  }
  function name(el, text) { if (el && el.getAttribute("aria-label") !== text) el.setAttribute("aria-label", text); }
  /** Names the playback bar's controls: the button by what pressing it does, the time field, the speed choice. */
  function nameControls() {
    const play = document.querySelector("svg.tabler-icon-player-play-filled, svg.tabler-icon-player-pause-filled");
    const button = play && play.closest("button");
    if (!button) return;
    name(button, play.classList.contains("tabler-icon-player-play-filled") ? I18n.t("Play") : I18n.t("Pause"));
    const bar = button.parentElement;
    const [time, speed] = bar.querySelectorAll("input:not([type=hidden])");  // the slider has a hidden one
    name(time, I18n.t("Time from the start of the recording, in seconds"));
    name(speed, I18n.t("Playback speed"));
  }
  function visit(root) {
    if (root.nodeType === Node.TEXT_NODE) { translateText(root); return; }
    if (root.nodeType !== Node.ELEMENT_NODE) return;
    translateAttributes(root);
    const walker = document.createTreeWalker(root, NodeFilter.SHOW_ELEMENT | NodeFilter.SHOW_TEXT);
    for (let node = walker.nextNode(); node; node = walker.nextNode()) {
      if (node.nodeType === Node.TEXT_NODE) translateText(node); else translateAttributes(node);
    }
  }

  const observer = new MutationObserver((records) => {
    for (const record of records) {
      if (record.type === "childList") record.addedNodes.forEach(visit);
      else if (record.type === "characterData") translateText(record.target);
      else translateAttributes(record.target);
    }
    nameControls();
  });
  observer.observe(document.documentElement, { childList: true, subtree: true, characterData: true,
    attributes: true, attributeFilter: ATTRIBUTES });
})();
