/* The pose landmarker in a worker (module worker, started by camera_pose.js; the watch's `two` in a second one,
 * started by the first: camera_pose_core.js), so that a detection (60-150 ms a frame on a slow CPU) does not hold
 * the page's main thread: the batch answers and the count are drawn meanwhile.
 * The landmarker is camera_pose_core.js; this file only carries its messages.
 * Messages in:  {type: "load", base, model, delegates, mode?, poses?, detection?} | {type: "detect", id, frame (transferred), ms}
 * Messages out: what camera_pose_core.js's load and detect answer. */
import { load, detect } from "./camera_pose_core.js";

self.onmessage = async ({ data }) => {
  if (data.type === "load") self.postMessage(await load(data));
  else if (data.type === "detect") self.postMessage(await detect(data));
};
