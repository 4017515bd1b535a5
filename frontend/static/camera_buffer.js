/* The camera set's buffer in the browser (IndexedDB): the running set and every batch not yet confirmed by the
 * server, so that a reload, a closed tab or a lost network loses nothing. Falls back to memory (no reload-resume)
 * where IndexedDB is not available (private windows of some browsers).
 *   sets:    {key: "<patient>", set_id, item_id, t0_ms, next_seq, ...}   one running set per patient
 *   batches: {key: "<set_id>/<seq padded>", set_id, seq, body}            sent in seq order, deleted once confirmed */
"use strict";
const CameraBuffer = (() => {
  const DB = "coach-camera", VERSION = 1;
  let db = null;
  const memory = { sets: new Map(), batches: new Map() };

  function open() {
    if (db !== null || !window.indexedDB) return Promise.resolve(db);
    return new Promise((resolve) => {
      const req = indexedDB.open(DB, VERSION);
      req.onupgradeneeded = () => {
        const d = req.result;
        if (!d.objectStoreNames.contains("sets")) d.createObjectStore("sets");
        if (!d.objectStoreNames.contains("batches")) d.createObjectStore("batches");
      };
      req.onsuccess = () => { db = req.result; resolve(db); };
      req.onerror = () => { db = null; resolve(null); };  // memory only
    });
  }

  function tx(store, mode, fn) {
    if (!db) return Promise.resolve(fn(null));
    return new Promise((resolve, reject) => {
      const t = db.transaction(store, mode);
      const s = t.objectStore(store);
      let out;
      const r = fn(s);
      if (r && "onsuccess" in r) r.onsuccess = () => { out = r.result; };
      t.oncomplete = () => resolve(out);
      t.onerror = () => reject(t.error);
      t.onabort = () => reject(t.error);
    });
  }

  const batchKey = (setId, seq) => `${setId}/${String(seq).padStart(8, "0")}`;

  async function putSet(patientId, state) {
    await open();
    if (!db) { memory.sets.set(String(patientId), state); return; }
    await tx("sets", "readwrite", (s) => s.put(state, String(patientId)));
  }

  async function getSet(patientId) {
    await open();
    if (!db) return memory.sets.get(String(patientId)) || null;
    return (await tx("sets", "readonly", (s) => s.get(String(patientId)))) || null;
  }

  /** Stores one batch and, when withSet ({patientId, state}) is given, the set's state in the same transaction
   * (one round trip: while it waits, the page's pose landmarker may hold the main thread). */
  async function putBatch(setId, seq, body, withSet) {
    await open();
    const row = { set_id: setId, seq, body };
    if (!db) {
      if (withSet) memory.sets.set(String(withSet.patientId), withSet.state);
      memory.batches.set(batchKey(setId, seq), row);
      return;
    }
    await new Promise((resolve, reject) => {
      const t = db.transaction(withSet ? ["batches", "sets"] : "batches", "readwrite");
      if (withSet) t.objectStore("sets").put(withSet.state, String(withSet.patientId));
      t.objectStore("batches").put(row, batchKey(setId, seq));
      t.oncomplete = () => resolve();
      t.onerror = () => reject(t.error);
      t.onabort = () => reject(t.error);
    });
  }

  async function batches(setId) {
    await open();
    const range = [batchKey(setId, 0), batchKey(setId, 99999999)];
    if (!db) return [...memory.batches.entries()].filter(([k]) => k >= range[0] && k <= range[1]).sort().map(([, v]) => v);
    return (await tx("batches", "readonly", (s) => s.getAll(IDBKeyRange.bound(range[0], range[1])))) || [];
  }

  async function dropBatch(setId, seq) {
    await open();
    if (!db) { memory.batches.delete(batchKey(setId, seq)); return; }
    await tx("batches", "readwrite", (s) => s.delete(batchKey(setId, seq)));
  }

  async function dropSet(patientId, setId) {
    await open();
    for (const b of await batches(setId)) await dropBatch(setId, b.seq);
    if (!db) { memory.sets.delete(String(patientId)); return; }
    await tx("sets", "readwrite", (s) => s.delete(String(patientId)));
  }

  return { open, putSet, getSet, putBatch, batches, dropBatch, dropSet, persistent: () => db !== null };
})();
