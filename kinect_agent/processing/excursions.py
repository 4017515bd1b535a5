"""Sustained tracking loss: a joint that jumps away faster than a body moves, sits there, and jumps back.

Per joint, over its present samples:

    jump     the speed between consecutive present samples exceeds the joint's limit (JOINT_SPEED_LIMIT_M_S:
             2 m/s trunk, 3 m/s elbows and knees, 4 m/s wrists, ankles, hands, feet) and is ABRUPTNESS (5) times the
             median speed of the surrounding steps; jump frames at most JUMP_GAP_FRAMES apart form one event
    away     an event that carries the joint at least min_dev_m (0.2 m) from the last sample before it (frame a),
             after at least min_len_s without a jump
    back     a later event, at least min_len_s (0.3 s) after it and within max_len_s (3 s) of its start, that ends at
             frame b within RETURN_FRACTION (0.3) of the jump away from where the joint left, followed by min_len_s
             without a jump
    sits     the samples between a and b lie, in median, at least min_dev_m from the straight line p[a] -> p[b], and
             their calm steps (below the speed limit) add up to no more than TRAVEL_FRACTION (0.5) of that distance
    limb     unless the joint's bone to its parent and its bones to its children all keep their typical length (in
             median within 5 cm or 20 %) while its parent is not away itself (a limb that really moved)

Every sample strictly between a and b is then an outlier (probability 1), combined with the temporal mixture by max
(combined_outliers.py); on by default (PipelineConfig.outlier_excursions). LiveExcursions is the causal form for the
online filter (PipelineConfig.online_excursions, on by default): a held joint that keeps its bones for LIMB_RELEASE_S
is let go. Why these rules and what each measured: bench/README.md, "Sustained excursions: how the rules were
chosen".
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from kinect_agent import skeleton
from kinect_agent.processing import _outliers_numba
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.recording import Recording
from kinect_agent.skeleton import NOT_TRACKED

_TRUNK = {"ROOT", "SPINE", "NECK", "HEAD", "SHO_L", "SHO_R", "HIP_L", "HIP_R"}
_MIDDLE = {"ELB_L", "ELB_R", "KNE_L", "KNE_R"}
JOINT_SPEED_LIMIT_M_S = np.array([2.0 if n in _TRUNK else 3.0 if n in _MIDDLE else 4.0 for n in skeleton.JOINTS])
JUMP_GAP_FRAMES = 3
CONTEXT_STEPS = 5  # steps on each side whose median speed a jump is compared with
ABRUPTNESS = 5.0  # a jump is this many times faster than the motion around it
RETURN_FRACTION = 0.3  # the jump back ends this close to where the jump away started, as a fraction of it
TRAVEL_FRACTION = 0.5  # a lost joint does not travel: calm-step travel at most this fraction of its distance
BONE_TOLERANCE_M, BONE_TOLERANCE_FRAC = 0.05, 0.2  # a limb that really moved keeps its bone to within these
BONE_EMA = 0.05  # per frame: the live rule's running bone lengths follow over about 20 frames
LIMB_RELEASE_S = 0.3  # a held joint that keeps its bones this long is a real limb: the live hold ends


def jump_events(t: np.ndarray, p: np.ndarray, speed_limit: float) -> list[tuple[int, int]]:
    """Returns [(first, last)] frame indices of the jump events of one joint, in time order.

    t: (T,) s. p: (T, 3) m, NaN = missing. A frame i is a jump frame when p[i - 1] and p[i] are both present, the
    speed |p[i] - p[i - 1]| / (t[i] - t[i - 1]) exceeds speed_limit (m/s) and it is ABRUPTNESS times the median
    speed of the other steps within CONTEXT_STEPS (fast motion accelerates; tracking loss teleports). Jump frames
    at most JUMP_GAP_FRAMES apart are merged. A recording of one frame has no step, so no jump.
    """
    if len(t) < 2:
        return []
    ok = np.all(np.isfinite(p), axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        speed = np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(t)  # (T - 1,) m/s, NaN across gaps
    fast = ok[1:] & ok[:-1] & (speed > speed_limit)
    calm = np.pad(np.where(fast, np.nan, speed), CONTEXT_STEPS, constant_values=np.nan)
    context = np.nan_to_num(window_nanmedian(calm, 2 * CONTEXT_STEPS + 1), nan=0.0)  # no calm step: any jump counts
    jumps = np.flatnonzero(fast & (speed > ABRUPTNESS * context)) + 1
    events: list[list[int]] = []
    for i in jumps:
        if events and i - events[-1][1] <= JUMP_GAP_FRAMES:
            events[-1][1] = int(i)
        else:
            events.append([int(i), int(i)])
    return [(a, b) for a, b in events]


def window_nanmedian(x: np.ndarray, w: int) -> np.ndarray:
    """Returns (len(x) − w + 1,): the median of the values of each window of w samples of x that are not NaN (NaN
    where there are none), as np.nanmedian of sliding_window_view(x, w) along its windows: compiled when numba is
    installed (_outliers_numba's running median: the same order statistics, their mean as 0.5 · (a + b), the same
    number as numpy's (a + b) / 2; only a median of two −0 differs, −0 against +0, equal to every comparison)."""
    if _outliers_numba.AVAILABLE and len(x) >= w:
        out = np.empty((1, len(x) - w + 1))
        _outliers_numba.running_median_kernel(np.ascontiguousarray(x, dtype=np.float64)[None, :], w, out)
        return out[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a window without a value: NaN
        return np.nanmedian(sliding_window_view(x, w), axis=1)


def _is_away(t: np.ndarray, p: np.ndarray, a: int, b: int, speed_limit: float, min_dev_m: float) -> bool:
    """True when p[a+1 .. b-1] sits, in median, at least min_dev_m from the straight line p[a] -> p[b] (linear in
    time), and does not travel there: summing only its steps below speed_limit (jumps left out), it gets no farther
    than TRAVEL_FRACTION of that distance from where it started. A lost joint sits, jitters or jumps; a limb that
    really moves away travels (UI-PRMD leg raises between two glitches at the top: 0.53-0.92 of the distance)."""
    frac = ((t[a + 1 : b] - t[a]) / (t[b] - t[a]))[:, None]
    dev = np.linalg.norm(p[a + 1 : b] - (p[a] + frac * (p[b] - p[a])), axis=1)
    if not np.any(np.isfinite(dev)):
        return False
    dev_m = float(np.nanmedian(dev))
    steps = np.diff(p[a + 1 : b], axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        calm = (np.linalg.norm(steps, axis=1) / np.diff(t[a + 1 : b]) <= speed_limit)[:, None]
    path = np.cumsum(np.where(calm, steps, 0.0), axis=0)
    travel = float(np.max(np.linalg.norm(path, axis=1))) if len(path) else 0.0
    return dev_m >= min_dev_m and travel <= TRAVEL_FRACTION * dev_m


def find_excursions(
    t: np.ndarray,
    p: np.ndarray,
    speed_limit: float,
    min_dev_m: float = 0.2,
    min_len_s: float = 0.3,
    max_len_s: float = 3.0,
) -> list[tuple[int, int]]:
    """Returns [(a, b)]: the excursions of one joint; the samples a+1 .. b-1 are away (module docstring).

    t: (T,) s. p: (T, 3) m, NaN = missing. Excursions do not overlap; each away-jump takes the first back-jump that
    qualifies. The joint must be calm (no jump) for min_len_s before the jump away and after the jump back: where
    the recording itself is garbage around a stretch (e.g. at the joins of UI-PRMD episodes), the stretch between
    is not the excursion.
    """
    events = jump_events(t, p, speed_limit)
    ok = np.all(np.isfinite(p), axis=1)

    def calm_between(i: int, j: int) -> bool:  # frames i < j at least min_len_s apart (i = -1 or j = T: the end)
        return i < 0 or j >= len(t) or t[j] - t[i] >= min_len_s - 1e-6

    found: list[tuple[int, int]] = []
    for k, (s1, e1) in enumerate(events):
        a = s1 - 1
        if (found and a < found[-1][1]) or not ok[a] or not calm_between(events[k - 1][1] if k else -1, s1):
            continue
        away = float(np.linalg.norm(p[e1] - p[a]))
        if away < min_dev_m:
            continue
        for m in range(k + 1, len(events)):
            s2, b = events[m]
            if t[b] - t[s1] > max_len_s:
                break
            if not calm_between(e1, s2) or np.linalg.norm(p[b] - p[a]) > RETURN_FRACTION * away:
                continue
            after = events[m + 1][0] if m + 1 < len(events) else len(t)
            if calm_between(b, after) and _is_away(t, p, a, b, speed_limit, min_dev_m):
                found.append((a, b))
                break
    return found


def bone_lengths(positions: np.ndarray) -> np.ndarray:
    """Returns (..., J) m: each joint's distance to its parent in positions (..., J, 3) m (NaN for ROOT and where an
    end is NaN)."""
    parents = np.maximum(skeleton.PARENT, 0)
    lengths = np.linalg.norm(positions - positions[..., parents, :], axis=-1)
    lengths[..., skeleton.PARENT < 0] = np.nan
    return lengths


def bone_tolerance(typical_m: np.ndarray | float) -> np.ndarray | float:
    """Returns how far (m) a bone of typical length typical_m may stray in a limb that really moved."""
    return np.maximum(BONE_TOLERANCE_M, BONE_TOLERANCE_FRAC * typical_m)


def _bone_kept(positions: np.ndarray, child: int, a: int, b: int, typical_m: np.ndarray) -> bool:
    """True when the bone from child's parent to child keeps its typical length (typical_m[child], m) during the
    span a+1 .. b-1, in median to within bone_tolerance."""
    bone = bone_lengths(positions[a + 1 : b])[:, child]
    if not np.any(np.isfinite(bone)) or not np.isfinite(typical_m[child]):
        return False
    return bool(float(np.nanmedian(np.abs(bone - typical_m[child]))) <= bone_tolerance(typical_m[child]))


def limb_kept(positions: np.ndarray, j: int, a: int, b: int, typical_m: np.ndarray) -> bool:
    """True when joint j moved as a body does during the span a+1 .. b-1: its bone to its parent and its bones to
    its children all keep their typical lengths (bone lengths typical_m (J,) m by child joint). A knee raised in a
    hurdle step keeps thigh and shank; an elbow the camera lost keeps the upper arm by chance but breaks the forearm
    (KERAAL). positions: (T, J, 3) m, NaN = missing."""
    children = np.flatnonzero(skeleton.PARENT == j)
    return all(_bone_kept(positions, c, a, b, typical_m) for c in (j, *children))


def excursion_probabilities(rec: Recording, config: PipelineConfig | None = None) -> np.ndarray:
    """Returns (T, J) in {0, 1}: 1 for the samples inside an excursion and where the joint is not tracked.

    An excursion of a joint whose limb keeps its bone lengths (limb_kept) is real motion and stays, unless the
    parent is itself away at the same time (a whole limb lost together keeps its inner bones). Parents come
    before children in skeleton.JOINTS, so a parent's excursions are settled first. Uses
    config.excursion_min_dev_m, excursion_min_len_s and excursion_max_len_s.
    """
    config = config or PipelineConfig()
    positions = np.where((rec.state != NOT_TRACKED)[..., None], rec.positions, np.nan)
    prob = np.where(rec.state == NOT_TRACKED, 1.0, 0.0)
    away = np.zeros(prob.shape, dtype=bool)
    typical = _typical_bones(positions)
    for j in range(positions.shape[1]):
        parent = int(skeleton.PARENT[j])
        spans = find_excursions(
            rec.t, positions[:, j], float(JOINT_SPEED_LIMIT_M_S[j]), config.excursion_min_dev_m,
            config.excursion_min_len_s, config.excursion_max_len_s,
        )  # fmt: skip
        for a, b in spans:
            if parent >= 0 and not away[a + 1 : b, parent].any() and limb_kept(positions, j, a, b, typical):
                continue
            away[a + 1 : b, j] = True
            prob[a + 1 : b, j] = 1.0
    return prob


def _typical_bones(positions: np.ndarray) -> np.ndarray:
    """Returns (J,) m: the median length of each joint's bone to its parent where both are present (NaN for ROOT
    and for bones never seen whole). positions: (T, J, 3) m, NaN = missing."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a bone never seen whole: NaN
        return np.nanmedian(bone_lengths(positions), axis=0)


class LiveExcursions:
    """The same rules, causal, for the online filter: a joint is held out from an abrupt jump away until it jumps
    back, travels, or max_len_s passes. What cannot be known yet is left out: the jump back is not required for
    the hold to start, and the abruptness context is the joint's last 2 · CONTEXT_STEPS calm steps only.

    A hold starts when a run of jump frames (gaps <= JUMP_GAP_FRAMES) carries the joint at least min_dev_m from
    where the run began, the joint having been calm for min_len_s before it. It ends at the frame that jumps back
    within RETURN_FRACTION of that distance (that frame is observed again), once the calm steps since the jump add
    up to more than TRAVEL_FRACTION of the joint's distance from where it left (it moved there: the limb is real),
    or after max_len_s, or once the joint has kept its bones to its parent and children for LIMB_RELEASE_S while
    its parent is not held (the limb rule, causal: a lost elbow may keep its upper arm when it jumps, and only the
    forearm shows it lost while it sits; a raised knee keeps thigh and shank throughout). The typical bone lengths
    are running averages over the frames where both ends are seen and neither is held (BONE_EMA per frame).
    """

    def __init__(self, min_dev_m: float = 0.2, min_len_s: float = 0.3, max_len_s: float = 3.0) -> None:
        J = skeleton.J
        self.min_dev_m, self.min_len_s, self.max_len_s = min_dev_m, min_len_s, max_len_s
        self.frame = 0
        self.last_p, self.last_t = np.full((J, 3), np.nan), np.full(J, np.nan)  # last present sample, m and s
        self.calm = np.zeros((J, 2 * CONTEXT_STEPS))  # each joint's last calm speeds, m/s (a ring)
        self.n_calm = np.zeros(J, dtype=np.int64)
        self.quiet_since = np.full(J, np.nan)  # s, start of the current stretch without jumps (NaN: in a run)
        self.run_last = np.full(J, -(10**9))  # frame of the last jump frame
        self.run_anchor = np.full((J, 3), np.nan)  # where the current jump run began, m
        self.run_calm = np.zeros(J, dtype=bool)  # the run began after min_len_s without a jump
        self.held = np.zeros(J, dtype=bool)
        self.leave = np.full((J, 3), np.nan)  # where a held joint left, m
        self.away = np.zeros(J)  # its jump distance, m
        self.path = np.zeros((J, 3))  # its calm steps since, summed, m
        self.hold_t = np.full(J, np.nan)  # s, when the hold began
        self.bone = np.full(J, np.nan)  # running typical length of each joint's bone to its parent, m
        self.limb_since = np.full(J, np.nan)  # s, since when a held joint has kept its bones (NaN: it has not)

    def step(self, t: float, positions: np.ndarray, present: np.ndarray) -> np.ndarray:
        """Returns (J,) bool: the joints to treat as missing in this frame.

        t: s, increasing. positions: (J, 3) m. present: (J,) bool, the joints observed in this frame.
        """
        k, self.frame = self.frame, self.frame + 1
        first = present & np.isnan(self.last_t)
        seen = present & ~first
        self.quiet_since[first] = t
        step = np.where(seen[:, None], positions - self.last_p, 0.0)
        with np.errstate(invalid="ignore"):
            speed = np.linalg.norm(step, axis=1) / np.maximum(t - self.last_t, 1e-6)
        context = np.median(self.calm, axis=1)  # ring starts at 0: no context yet, any fast step counts
        jump = seen & (speed > JOINT_SPEED_LIMIT_M_S) & (speed > ABRUPTNESS * context)
        new_run = jump & (k - self.run_last > JUMP_GAP_FRAMES)
        self.run_anchor[new_run] = self.last_p[new_run]
        quiet = self.last_t - self.quiet_since  # NaN while in a run
        self.run_calm[new_run] = quiet[new_run] >= self.min_len_s - 1e-6
        self.run_last[jump], self.quiet_since[jump] = k, np.nan
        calm = np.flatnonzero(seen & ~jump)
        self.calm[calm, self.n_calm[calm] % self.calm.shape[1]] = speed[calm]
        self.n_calm[calm] += 1
        resumed = seen & ~jump & np.isnan(self.quiet_since) & (k - self.run_last > JUMP_GAP_FRAMES)
        self.quiet_since[resumed] = t

        was_held = seen & self.held
        distance = np.linalg.norm(positions - self.leave, axis=1)
        self.path[was_held & ~jump] += step[was_held & ~jump]
        self.away = np.where(was_held & jump, np.fmax(self.away, distance), self.away)  # landing takes 2-3 frames
        back = was_held & jump & (distance <= RETURN_FRACTION * self.away)
        travelled = was_held & ~jump & (np.linalg.norm(self.path, axis=1) > TRAVEL_FRACTION * distance)
        limb = was_held & self._limbs_kept(positions, present)
        self.limb_since = np.where(limb, np.fmin(self.limb_since, t), np.nan)
        limb_real = limb & (t - self.limb_since >= LIMB_RELEASE_S - 1e-6)
        release = back | travelled | limb_real | (was_held & (t - self.hold_t > self.max_len_s))
        self.held[release], self.quiet_since[release] = False, t
        out = was_held & ~release

        leave = np.linalg.norm(positions - self.run_anchor, axis=1)
        start = seen & ~self.held & ~release & jump & self.run_calm & (leave >= self.min_dev_m)
        self.held[start] = True
        self.leave[start], self.away[start], self.path[start], self.hold_t[start] = (
            self.run_anchor[start], leave[start], 0.0, t,
        )  # fmt: skip
        out |= start
        self._learn_bones(positions, present & ~out)
        self.last_p[present], self.last_t[present] = positions[present], t
        return out

    def _bone_lengths(self, positions: np.ndarray, present: np.ndarray) -> np.ndarray:
        """Returns (J,) m: each joint's distance to its parent this frame (NaN where an end is missing, and ROOT)."""
        both = present & present[np.maximum(skeleton.PARENT, 0)]
        return np.where(both, bone_lengths(positions), np.nan)

    def _learn_bones(self, positions: np.ndarray, usable: np.ndarray) -> None:
        """Updates the running bone lengths from the bones whose two ends are usable (seen, not held)."""
        lengths = self._bone_lengths(positions, usable)
        new = np.isfinite(lengths) & np.isnan(self.bone)
        self.bone[new] = lengths[new]
        update = np.isfinite(lengths) & ~new
        self.bone[update] += BONE_EMA * (lengths[update] - self.bone[update])

    def _limbs_kept(self, positions: np.ndarray, present: np.ndarray) -> np.ndarray:
        """Returns (J,) bool: the joints whose bones to parent and children all keep their running length this
        frame, their parent not held (False where a length is not known: no release without evidence)."""
        lengths = self._bone_lengths(positions, present)
        fits = np.abs(lengths - self.bone) <= bone_tolerance(self.bone)
        parents = np.maximum(skeleton.PARENT, 0)
        children_fit = np.ones(skeleton.J, dtype=bool)
        np.logical_and.at(children_fit, parents[1:], fits[1:])  # each joint: all of its children's bones fit
        return (skeleton.PARENT >= 0) & fits & children_fit & ~self.held[parents]
