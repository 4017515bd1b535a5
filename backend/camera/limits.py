"""What a camera set may send: sizes, rates and the ranges of plausible landmark values (one place for all)."""

from __future__ import annotations

N_LANDMARKS = 33  # BlazePose's landmarks per frame
MAX_FRAMES_PER_BATCH = 120  # 4 s at 30 fps: a page sends every ~0.1 s, or its buffer after a network loss
MAX_FPS = 60.0  # frames the set's clock may hold per second (a landmarker in a browser gives 5-30)
MAX_BATCHES_PER_S = 20.0  # batches per second of wall-clock time since the start, on average
RATE_SLACK_S = 10.0  # seconds of allowance in both rate limits (a burst after a reload or a lost network)
MAX_SET_S = 1800.0  # the set's clock: frame times 0 <= t <= MAX_SET_S seconds
MAX_CLOCK_AHEAD_S = 5.0  # frame times may run ahead of the server's clock since the start by this much
MAX_WORLD_M = 3.0  # world landmarks (metres, about the hips' centre): |x|, |y|, |z| at most this
IMAGE_XY_RANGE = (-1.0, 2.0)  # image landmarks (normalised to the frame; a limb may reach outside it)
MAX_IMAGE_Z = 10.0  # image landmarks' relative depth, |z| at most this
MIN_END_FRAMES = 10  # a set with fewer frames cannot be analysed: it ends as failed, nothing stored
CONSENT_VERSION = "2026-11-27"  # the consent text the page shows (docs/camera-sets.md); a new text asks again
MODELS = ("pose_landmarker_lite", "pose_landmarker_full")  # the pinned models the page may run
