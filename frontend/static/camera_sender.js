/* Sends a camera set's batches to the server in order, from the browser's buffer (CameraBuffer): each batch is
 * written to the buffer first and deleted once the server confirmed it (201 new, 200 received before). A lost
 * network is retried every RETRY_MS and said once; a refused batch (4xx) stops the set with its reason.
 * Sending does not wait for the buffer: a batch goes to the server from memory (queue) while IndexedDB writes it
 * (a write took 0.2-2 s on a busy 2-core machine, and each round trip may also wait for the pose landmarker, which
 * holds the page's main thread for 60-150 ms a frame), and the answer (the count) is shown before the buffer's
 * delete. The server stores each batch number once (a repeat is answered 200), and IndexedDB commits a page's
 * writes in order, so after a crash the buffer holds a prefix of the batches: the page resumes after the larger of
 * the buffer's and the server's last batch (camera_page.js resume). After a reload the queue starts from the
 * buffer. */
"use strict";
const CameraSender = (() => {
  const { api } = Coach;
  const RETRY_MS = 2000;
  let setId = null, running = false, offline = false, stopped = null, handlers = {}, failures = 0;
  let queue = [], loaded = false, writes = new Set();

  /** Sends the batches of set id from now on; fresh: a set just started (nothing of it in the buffer to read). */
  function init(id, on, fresh) {
    if (id !== setId) { queue = []; loaded = Boolean(fresh); }
    setId = id; handlers = on; stopped = null;
  }

  function enqueue(b) {
    if (queue.some((q) => q.seq === b.seq)) return;
    queue.push({ seq: b.seq, body: b.body });
    queue.sort((x, y) => x.seq - y.seq);
  }

  /** Keeps a buffer write (or delete) until it is done; drain waits for them. */
  function track(promise) {
    const done = promise.catch((err) => console.error(err)).finally(() => writes.delete(done));
    writes.add(done);
    return done;
  }

  /** Buffers one batch (with the set's state when withSet = {patientId, state} is given: one transaction) and
   * sends it at once, without waiting for the buffer or the network. */
  function add(seq, body, withSet) {
    const stored = track(CameraBuffer.putBatch(setId, seq, body, withSet));
    queue.push({ seq, body, stored });
    queue.sort((x, y) => x.seq - y.seq);
    pump();
  }

  function say(isOffline) {
    if (isOffline === offline) return;
    offline = isOffline;
    if (handlers.network) handlers.network(!offline);
  }

  /** Deletes a confirmed batch from the buffer once its write is done. */
  function drop(id, b) {
    track((b.stored || Promise.resolve()).then(() => CameraBuffer.dropBatch(id, b.seq)));
  }

  /** Sends every queued batch in order; returns when the queue is empty (or sending stopped). */
  async function pump() {
    if (running || !setId || stopped) return;
    running = true;
    try {
      if (!loaded) {
        const id = setId;
        for (const b of await CameraBuffer.batches(id)) if (id === setId) enqueue(b);
        loaded = id === setId;
      }
      while (queue.length) {
        const b = queue[0], id = setId;
        try {
          const sent = Date.now();
          const out = await api(`/camera/sets/${id}/batches`, { method: "POST", body: b.body });
          const answered = Date.now();
          if (queue[0] === b) queue.shift();
          failures = 0;
          say(false);
          if (handlers.answer) handlers.answer(out, b.body, { sent, answered });  // the count first, then the delete
          drop(id, b);
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

  /** Resolves once every buffered batch was confirmed and deleted from the buffer (waits through a lost network;
   * rejects when refused). */
  async function drain() {
    for (;;) {
      if (stopped) throw stopped;
      await pump();
      if (loaded && !queue.length && !running) {
        await Promise.all([...writes]);
        if (!(await CameraBuffer.batches(setId)).length) return;
        loaded = false;  // something is in the buffer that the queue does not hold: read it again
      }
      await new Promise((r) => setTimeout(r, 300));
    }
  }

  window.addEventListener("online", () => pump());
  window.addEventListener("offline", () => say(true));
  /** What the sender holds (for CameraPage.state(): tests and benchmarks). */
  function state() {
    return { queued: queue.map((b) => b.seq), running, loaded, writes: writes.size, offline, failures,
      stopped: stopped ? String(stopped.error || stopped) : null };
  }

  return { init, add, pump, drain, state, isOffline: () => offline, idle: () => !running };
})();
