/* Sends a camera set's batches to the server in order, from the browser's buffer (CameraBuffer): each batch is
 * written to the buffer first and deleted once the server confirmed it (201 new, 200 received before). A lost
 * network is retried every RETRY_MS and said once; a refused batch (4xx) stops the set with its reason. */
"use strict";
const CameraSender = (() => {
  const { api } = Coach;
  const RETRY_MS = 2000;
  let setId = null, running = false, offline = false, stopped = null, handlers = {}, failures = 0;

  function init(id, on) { setId = id; handlers = on; stopped = null; }

  /** Buffers one batch and starts sending (never waits for the network). */
  async function add(seq, body) {
    await CameraBuffer.putBatch(setId, seq, body);
    pump();
  }

  function say(isOffline) {
    if (isOffline === offline) return;
    offline = isOffline;
    if (handlers.network) handlers.network(!offline);
  }

  /** Sends every buffered batch in order; returns when the buffer is empty (or sending stopped). */
  async function pump() {
    if (running || !setId || stopped) return;
    running = true;
    try {
      for (;;) {
        const pending = await CameraBuffer.batches(setId);
        if (!pending.length) break;
        const b = pending[0];
        try {
          const out = await api(`/camera/sets/${setId}/batches`, { method: "POST", body: b.body });
          await CameraBuffer.dropBatch(setId, b.seq);
          failures = 0;
          say(false);
          if (handlers.answer) handlers.answer(out, b.body);
        } catch (err) {
          if (err.status === 0 || err.status >= 500 || err.status === 429) {
            say(err.status === 0 ? true : offline);
            failures = err.status >= 500 ? failures + 1 : 0;
            if (failures === 3 && handlers.trouble) handlers.trouble();  // said once; sending goes on
            await new Promise((r) => setTimeout(r, err.status === 429 ? 1000 : RETRY_MS));
            continue;
          }
          stopped = err;
          if (handlers.refused) handlers.refused(err);
          break;
        }
      }
    } finally { running = false; }
  }

  /** Resolves once every buffered batch was confirmed (waits through a lost network; rejects when refused). */
  async function drain() {
    for (;;) {
      if (stopped) throw stopped;
      await pump();
      if (!(await CameraBuffer.batches(setId)).length) return;
      await new Promise((r) => setTimeout(r, 300));
    }
  }

  window.addEventListener("online", () => pump());
  window.addEventListener("offline", () => say(true));
  return { init, add, pump, drain, isOffline: () => offline, idle: () => !running };
})();
