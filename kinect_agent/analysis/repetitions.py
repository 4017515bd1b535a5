"""Repetition counting from an exercise's defining joint angle(s): one repetition is one excursion of a defining
angle away from its rest level and back. Why each rule is there, with the recordings that asked for it:
bench/README.md, "Repetition counter: why each rule".

Per angle (detect_angle):
    1. the series is conditioned (series.smooth: gaps filled, unwrapped, median then Gaussian smoothed);
    2. its range R = p98 − p2; an angle with R < min_range_deg, or below side_ratio × the largest R among the
       exercise's angles, yields no repetitions;
    3. the rest level is the end (p2 or p98) nearer to the first and the last smoothed value; when those disagree,
       the end the signal spends more time near; when it spends as long near either, the end whose excursions number
       closest to duration / P (P: the autocorrelation's period); with rest="start" (a set still being recorded),
       the end nearer to the median of its first START_S seconds. The excursion e(t) = |angle − rest level|,
       clipped to [0, R]; its cycle (cycles.cycle): period P and typical amplitude A (R without a period); e is
       then taken from its lower envelope over 1.5 P (cycles.baseline);
    4. hysteresis: an excursion begins when e rises above enter_frac·A and ends when it falls below exit_frac·A;
    5. each excursion is widened to its onset and return: between the neighbouring excursions, the repetition starts
       at the last frame (ends at the first) whose e is within onset_frac·A of that stretch's minimum; excursions
       shorter than min_duration_s are dropped.
Amplitude = e at the peak minus the mean rest e just before and after (degrees); peak = the smoothed angle at the
peak (degrees); side = "left"/"right" from the angle's _L/_R suffix, "center" otherwise; core = the frames around the
peak where e stays at least half the amplitude above the rest.

Several angles (count_repetitions), in this order; M, D: the median amplitude and duration of the excursions still
counted; each rule's exact form is the docstring of the function named:
    - the dominant angle is the one whose excursions add up to the most degrees (Σ amplitude); an angle without a
      period of its own whose autocorrelation at the dominant's period is below cycles.MIN_CORRELATION idles
      (_repeating);
    - excursions of different angles that overlap and whose cores meet are one repetition, side "both" (merge_events);
    - a one-sided repetition counts on the dominant side or a side that alternates with it (_alternates); when at
      least half are "both", only if it reaches lone_ratio × their median amplitude (_drop_weak_lone);
    - below min_ratio × M is a bump, unless it reaches shallow_ratio × M and lasts shallow_duration × D (_drop_bumps);
    - a brief excursion that peaks close to a larger one is a rebound (_drop_rebounds); a shallow one with no slot of
      the cadence of its own is dropped (_drop_off_cadence); a shallow repetition the hysteresis missed is added where
      the cadence has room for one, it rises add_rise_ratio × M above both sides, the rest levels of its two sides
      are within add_levels_frac × M and it lasts a repetition's time, measured at half its own rise
      (_add_shallow, add_half_width);
    - last, with min_amplitude_deg > 0 (a device's floor, kinect_agent.analysis.live.amplitude_floor), an excursion
      with a smaller amplitude is dropped.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from kinect_agent.analysis import cycles, series

TIE_DWELL = 0.05  # |share of time below the middle − 0.5| under which neither end is the rest level
START_S = 1.0  # rest="start": the start level is the median of this many seconds from the first frame


@dataclass(frozen=True)
class RepetitionParams:
    """Thresholds of the repetition detector; fractions are of the angle's own range R."""

    enter_frac: float = 0.3
    exit_frac: float = 0.2
    onset_frac: float = 0.1
    min_range_deg: float = 10.0
    side_ratio: float = 0.35
    alternate_shared: float = 0.2
    alternate_overlap: float = 0.2
    lone_ratio: float = 0.6
    min_ratio: float = 0.4
    shallow_ratio: float = 0.2
    shallow_duration: float = 0.6
    shallow_spacing: float = 0.8  # × the median peak-to-peak spacing: the least room between two peaks
    min_duration_s: float = 0.4
    merge_overlap: float = 0.5
    min_amplitude_deg: float = 0.0  # last: an excursion with a smaller amplitude is no repetition (0: no such rule)
    slot_keeps_shallow: bool = False  # a brief shallow excursion with a cadence slot of its own counts (_own_slot)
    add_spacing_pct: float = 33.0  # percentile of the peak-to-peak spacings that sets the room _add_shallow searches
    add_half_width: bool = True  # _add_shallow: a missed shallow one's width at half its rise against the cores
    # _add_shallow's rise above both sides and how far apart its two sides' rest levels may be, × the counted ones'
    # median amplitude M (levels: 0.1 until 2026-11-28, chosen leave one subject out; bench/README.md)
    add_rise_ratio: float = 0.2
    add_levels_frac: float = 0.3
    rest: str = "auto"  # "auto": step 3 of the module doc; "start": where the recording starts (a set counted live)


@dataclass(frozen=True)
class Repetition:
    """One repetition: times in seconds from the recording's first frame, angles in degrees."""

    index: int
    start_s: float
    end_s: float
    duration_s: float
    amplitude_deg: float
    peak_deg: float
    side: str
    peak_s: float = 0.0  # time of the peak, seconds from the recording's first frame

    def to_dict(self) -> dict[str, object]:
        """Returns the JSON-ready form (floats rounded to 1 ms and 0.1°)."""
        d = asdict(self)
        for key in ("start_s", "end_s", "duration_s", "peak_s"):
            d[key] = round(d[key], 3)
        for key in ("amplitude_deg", "peak_deg"):
            d[key] = round(d[key], 1)
        return d


@dataclass(frozen=True)
class RepEvent:
    """One excursion of one angle (or of both sides once merged): frames of onset, peak and end."""

    start: int  # frame of onset
    peak: int
    end: int  # frame of return
    amplitude: float
    peak_deg: float
    side: str
    angles: tuple[str, ...]
    core_start: int = -1  # first frame of the core (module doc), −1: not known, the start
    core_end: int = -1  # last frame of the core, −1: not known, the end

    @property
    def core(self) -> tuple[int, int]:
        """Returns (first, last) frame of the excursion's core, where it stands at least half its amplitude above
        its rest (start and end when not known)."""
        return (
            self.start if self.core_start < 0 else self.core_start,
            self.end if self.core_end < 0 else self.core_end,
        )


@dataclass(frozen=True)
class RepetitionResult:
    """Repetitions of one recording; ranges_deg: R per defining angle; moving: the angles that moved."""

    repetitions: list[Repetition]
    defining_angle: str | None
    ranges_deg: dict[str, float]
    moving: tuple[str, ...]


def side_of(angle: str) -> str:
    """Returns "left", "right" or "center" from an angle name's _L/_R suffix."""
    return {"_L": "left", "_R": "right"}.get(angle[-2:], "center")


def angle_range(x: np.ndarray) -> float:
    """Returns R = p98 − p2 of a smoothed series x: (T,) degrees (0 when nothing is finite)."""
    finite = x[np.isfinite(x)]
    if finite.size == 0:
        return 0.0
    lo, hi = np.percentile(finite, [2.0, 98.0])
    return float(hi - lo)


def _hysteresis(e: np.ndarray, enter: float, leave: float) -> np.ndarray:
    """Returns (T,) bool: True inside an excursion (entered above `enter`, left below `leave`)."""
    mark = np.where(e > enter, 1, np.where(e < leave, 0, -1))
    idx = np.where(mark >= 0, np.arange(e.shape[0]), 0)
    np.maximum.accumulate(idx, out=idx)
    return mark[idx] == 1  # frames before the first decision read mark[0] = -1: at rest


def _rest_is_low(y: np.ndarray, lo: float, hi: float, rest: str = "auto", start_frames: int = 1) -> bool | None:
    """True when the rest level is the low end: where the recording starts and ends, else where it stays longer
    (rest="start": where the median of its first start_frames frames lies); None when start and end disagree and it
    stays as long at either end (within TIE_DWELL of half the time: a symmetric oscillation, e.g. shoulder
    rotation)."""
    mid = 0.5 * (lo + hi)
    if rest == "start":
        return bool(np.median(y[: max(1, start_frames)]) < mid)
    start_low, end_low = y[0] < mid, y[-1] < mid
    if start_low == end_low:
        return bool(start_low)
    low_share = float(np.mean(y < mid))
    if abs(low_share - 0.5) < TIE_DWELL:
        return None
    return low_share >= 0.5


def detect(t: np.ndarray, y: np.ndarray, name: str, params: RepetitionParams) -> list[RepEvent]:
    """Returns the excursions of one smoothed angle y: (T,) degrees at t: (T,) s (steps 3-5 of the module doc)."""
    return detect_angle(t, y, name, params).events


@dataclass(frozen=True)
class AngleExcursions:
    """The excursions of one angle; n_cycles: duration / P of its period (0 without one); rest_low: its rest end is
    the low one; rest_deg: that end (p2 or p98 of the smoothed angle, degrees); cycle_deg: A."""

    events: list[RepEvent]
    n_cycles: int
    rest_low: bool
    rest_deg: float
    cycle_deg: float = 0.0  # A of step 3 (degrees): its cycle's typical amplitude, or its range when it has none


def _found(tried: tuple[list[RepEvent], int, float], rest_low: bool, rest_deg: float) -> AngleExcursions:
    """Returns the AngleExcursions of _excursions' (events, n_cycles, cycle_deg) at that rest end."""
    events, n_cycles, cycle_deg = tried
    return AngleExcursions(events, n_cycles, rest_low, rest_deg, cycle_deg)


def detect_angle(
    t: np.ndarray, y: np.ndarray, name: str, params: RepetitionParams, bounds: tuple[float, float] | None = None
) -> AngleExcursions:
    """Returns the excursions of one smoothed angle y: (T,) degrees at t: (T,) s, its cycles and its rest end.

    bounds: (p2, p98) of y when already computed. When the rest end is a tie (_rest_is_low gives None), both ends are
    tried and the one whose number of excursions is nearer the number of cycles the autocorrelation's period gives
    wins (the low end on a tie).
    """
    lo, hi = bounds if bounds is not None else np.percentile(y, [2.0, 98.0])
    if hi - lo <= 0:
        return AngleExcursions([], 0, True, float(lo))
    start_frames = int(round(START_S / series.frame_interval(t))) if params.rest == "start" else 1
    rest_low = _rest_is_low(y, lo, hi, params.rest, start_frames)
    if rest_low is not None:
        return _found(_excursions(t, y, name, params, rest_low), rest_low, float(lo if rest_low else hi))
    tries = [_found(_excursions(t, y, name, params, low), low, float(lo if low else hi)) for low in (True, False)]
    return min(tries, key=lambda tried: abs(len(tried.events) - tried.n_cycles))


def _excursions(
    t: np.ndarray, y: np.ndarray, name: str, params: RepetitionParams, rest_low: bool
) -> tuple[list[RepEvent], int, float]:
    """Returns (the excursions of y: (T,) degrees away from its low (rest_low) or high end, the cycles its period
    gives: duration / P, 0 without a period, the cycle amplitude A in degrees)."""
    lo, hi = np.percentile(y, [2.0, 98.0])
    R = float(hi - lo)
    e = np.clip(y - lo if rest_low else hi - y, 0.0, R)
    cyc = cycles.cycle(t, e)
    e = e - cycles.baseline(t, e, cyc)
    R = cyc.amplitude_deg if cyc.amplitude_deg > 0 else R
    inside = _hysteresis(e, params.enter_frac * R, params.exit_frac * R)
    edges = np.flatnonzero(np.diff(np.concatenate(([0], inside.astype(np.int8), [0]))))
    runs = edges.reshape(-1, 2)  # [first, stop) of each excursion core
    n_cycles = cyc.n_cycles if cyc.period_s is not None else 0
    if runs.shape[0] == 0:
        return [], n_cycles, R
    start, end, base0, base1 = _widen(e, runs, inside, params.onset_frac * R)
    peak = _run_argmax(e, runs)
    keep = t[end] - t[start] >= params.min_duration_s
    amplitude = e[peak] - 0.5 * (base0 + base1)
    core0, core1 = _cores(e, start, peak, np.minimum(end, e.shape[0] - 1), e[peak] - 0.5 * amplitude)
    side = side_of(name)
    events = [
        RepEvent(int(a), int(p), int(b), float(amp), float(y[p]), side, (name,), int(c0), int(c1))
        for a, p, b, amp, c0, c1 in zip(
            start[keep], peak[keep], end[keep], amplitude[keep], core0[keep], core1[keep], strict=True
        )
    ]
    return events, n_cycles, R


def _cores(
    e: np.ndarray, start: np.ndarray, peak: np.ndarray, end: np.ndarray, half: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Returns (first, last) frames, each (n,), of the core of each excursion of e: (T,) degrees: the frames around
    its peak (start <= peak <= end, (n,) frames each) where e stays at or above half: (n,) degrees."""
    T = e.shape[0]
    idx = np.arange(T)
    first = start.astype(np.int64).copy()
    seg = _segment_ids(T, start, peak + 1)
    low = (seg >= 0) & (e < half[np.maximum(seg, 0)])
    np.maximum.at(first, seg[low], idx[low] + 1)
    last = end.astype(np.int64).copy()
    seg = _segment_ids(T, peak, end + 1)
    low = (seg >= 0) & (e < half[np.maximum(seg, 0)])
    np.minimum.at(last, seg[low], idx[low] - 1)
    return np.minimum(first, peak), np.maximum(last, peak)


def _gap_minima(e: np.ndarray, runs: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """Returns (n + 1,) the minimum of e: (T,) in each gap around the n runs ([first, stop) frames, in order, of the
    True stretches of inside: (T,) bool): gap k is [stop of run k − 1 (0 for k = 0), first of run k (T for k = n));
    +inf for an empty gap."""
    T = e.shape[0]
    lo = np.concatenate(([0], runs[:, 1]))
    hi = np.concatenate((runs[:, 0], [T]))
    out = np.full(lo.shape[0], np.inf)
    full = hi > lo
    if full.any():
        sizes = (hi - lo)[full]
        offsets = np.concatenate(([0], np.cumsum(sizes)[:-1]))
        out[full] = np.minimum.reduceat(e[~inside], offsets)  # the gaps are the frames outside, in order
    return out


def _segment_ids(T: int, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Returns (T,) int: k for the frames of segment k = [lo[k], hi[k]) (disjoint, in order), −1 elsewhere."""
    seg = np.full(T, -1, dtype=np.int64)
    for k, (a, b) in enumerate(zip(lo, hi, strict=True)):
        seg[a:b] = k
    return seg


def _widen(
    e: np.ndarray, runs: np.ndarray, inside: np.ndarray, onset: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Widens each run ([first, stop) frames of an excursion core, (n, 2); the True stretches of inside: (T,) bool)
    of e: (T,) degrees to its onset and return (step 5 of the module doc). Returns (start, end, base0, base1), each
    (n,): the last frame before the core (first frame after it) within `onset` degrees of the minimum of the
    stretch back to the previous core (on to the next), and those two minima."""
    T = e.shape[0]
    first, stop = runs[:, 0], runs[:, 1]
    gap = _gap_minima(e, runs, inside)
    base0 = np.minimum(gap[:-1], e[first])  # stretch [previous stop, first]
    base1 = np.minimum(e[stop - 1], gap[1:])  # stretch [stop − 1, next first)
    prev_stop = np.concatenate(([0], stop[:-1]))
    next_first = np.concatenate((first[1:], [T]))
    idx = np.arange(T)
    # onset: the last frame of [previous stop, first] at or under base0 + onset
    seg = _segment_ids(T, prev_stop, first + 1)
    ok = (seg >= 0) & (e <= base0[seg] + onset)
    start = np.zeros(runs.shape[0], dtype=np.int64)
    np.maximum.at(start, seg[ok], idx[ok])
    # return: the first frame of [stop − 1, next first) at or under base1 + onset
    seg = _segment_ids(T, stop - 1, next_first)
    ok = (seg >= 0) & (e <= base1[seg] + onset)
    end = np.full(runs.shape[0], T, dtype=np.int64)
    np.minimum.at(end, seg[ok], idx[ok])
    return start, end, base0, base1


def _run_argmax(e: np.ndarray, runs: np.ndarray) -> np.ndarray:
    """Returns (n,) the frame of each run's maximum of e: (T,) (its first, as np.argmax)."""
    seg = _segment_ids(e.shape[0], runs[:, 0], runs[:, 1])
    inside = seg >= 0
    top = np.maximum.reduceat(e[inside], np.concatenate(([0], np.cumsum(runs[:, 1] - runs[:, 0])[:-1])))
    idx = np.flatnonzero(inside & (e == top[np.maximum(seg, 0)]))
    peak = np.full(runs.shape[0], e.shape[0], dtype=np.int64)
    np.minimum.at(peak, seg[idx], idx)
    return peak


def _shared(a: RepEvent, b: RepEvent) -> int:
    """Frames two events share (0 when they do not overlap)."""
    return max(0, min(a.end, b.end) - max(a.start, b.start))


def merge_events(events: list[RepEvent], overlap: float) -> list[RepEvent]:
    """Joins events of different angles that overlap by more than `overlap` of the shorter one and whose cores
    meet (both sides at least half their amplitude up at one moment).

    When an event of a side already in the group overlaps the group's other members more than that side's member
    does (a bump just before the real excursion of one knee paired first with the other knee's excursion), the
    event takes the member's place and the member stands alone.
    """
    merged: list[list[RepEvent]] = []
    g_start = g_end = 0  # frames spanned by the last group, merged[-1]
    c_start = c_end = 0  # frames spanned by the cores of the last group
    for ev in sorted(events, key=lambda ev: ev.start):
        e0, e1 = ev.core
        if merged:
            group = merged[-1]
            shared = min(g_end, ev.end) - max(g_start, ev.start)
            shorter = max(1, min(g_end - g_start, ev.end - ev.start))
            meet = min(c_end, e1) >= max(c_start, e0)
            if shared > overlap * shorter and meet:
                same = [x for x in group if x.side == ev.side]
                if not same:
                    group.append(ev)
                    g_start, g_end = min(g_start, ev.start), max(g_end, ev.end)
                    c_start, c_end = min(c_start, e0), max(c_end, e1)
                    continue
                others = [x for x in group if x.side != ev.side]
                rival = same[0]
                if others and sum(_shared(ev, o) for o in others) > sum(_shared(rival, o) for o in others):
                    group.remove(rival)
                    group.append(ev)
                    merged.insert(len(merged) - 1, [rival])
                    g_start, g_end = min(x.start for x in group), max(x.end for x in group)
                    c_start, c_end = min(x.core[0] for x in group), max(x.core[1] for x in group)
                    continue
        merged.append([ev])
        g_start, g_end = ev.start, ev.end
        c_start, c_end = e0, e1
    out = []
    for group in merged:
        if len(group) == 1:
            out.append(group[0])
            continue
        out.append(
            RepEvent(
                start=min(x.start for x in group),
                peak=max(group, key=lambda x: x.amplitude).peak,
                end=max(x.end for x in group),
                amplitude=_mean([x.amplitude for x in group]),
                peak_deg=_mean([x.peak_deg for x in group]),
                side="both",
                angles=tuple(a for x in group for a in x.angles),
                core_start=min(x.core[0] for x in group),
                core_end=max(x.core[1] for x in group),
            )
        )
    return sorted(out, key=lambda ev: ev.start)


def _mean(values: list[float]) -> float:
    """The mean of a few floats (a merged group's; np.mean's call costs more than the sum)."""
    return sum(values) / len(values)


def _keep_counted(merged: list[RepEvent], counted: set[str]) -> list[RepEvent]:
    return [ev for ev in merged if counted & set(ev.angles)]


def _drop_weak_lone(merged: list[RepEvent], lone_ratio: float) -> list[RepEvent]:
    """In a bilateral session (at least half the events "both"), drops one-sided events below lone_ratio × median."""
    both = [ev.amplitude for ev in merged if ev.side == "both"]
    if not merged or 2 * len(both) < len(merged):
        return merged
    floor = lone_ratio * float(np.median(both))
    return [ev for ev in merged if ev.side == "both" or ev.amplitude >= floor]


def _drop_bumps(merged: list[RepEvent], params: RepetitionParams) -> list[RepEvent]:
    """Drops the excursions below min_ratio × the median amplitude, except those above shallow_ratio × it that last
    at least shallow_duration × the median duration (a shallow repetition takes a repetition's time, a bump not) or,
    with slot_keeps_shallow, that have a slot of the cadence of their own (_own_slot)."""
    if not merged:
        return merged
    amplitude = float(np.median([ev.amplitude for ev in merged]))
    duration = float(np.median([ev.end - ev.start for ev in merged]))
    shallow_floor, long_enough = params.shallow_ratio * amplitude, params.shallow_duration * duration
    slot = _own_slot(merged, params) if params.slot_keeps_shallow else np.zeros(len(merged), dtype=bool)
    return [
        ev
        for ev, own in zip(merged, slot, strict=True)
        if ev.amplitude >= params.min_ratio * amplitude
        or (ev.amplitude >= shallow_floor and (own or ev.end - ev.start >= long_enough))
    ]


def _own_slot(merged: list[RepEvent], params: RepetitionParams) -> np.ndarray:
    """Returns (n,) bool, in merged's order: the excursion peaks at least shallow_spacing × S from the peak of every
    full repetition (at least min_ratio × the median amplitude; S: their median peak-to-peak spacing), on each side
    that has one. A repetition done shallow takes a place of the cadence; a bump at rest sits beside a full one.
    False for all with fewer than three full repetitions."""
    peaks = np.array([ev.peak for ev in merged])  # (n,) frames
    amplitude = np.array([ev.amplitude for ev in merged])  # (n,) degrees
    full_peaks = np.sort(peaks[amplitude >= params.min_ratio * float(np.median(amplitude))])
    if full_peaks.size < 3:
        return np.zeros(len(merged), dtype=bool)
    room = params.shallow_spacing * float(np.median(np.diff(full_peaks)))
    k = np.searchsorted(full_peaks, peaks)
    before = np.where(k > 0, peaks - full_peaks[np.maximum(k - 1, 0)], np.inf)
    after = np.where(k < full_peaks.size, full_peaks[np.minimum(k, full_peaks.size - 1)] - peaks, np.inf)
    return np.asarray((before >= room) & (after >= room))


def _alternates(name: str, dominant: str, events: list[RepEvent], params: RepetitionParams, cycle_deg: float) -> bool:
    """True when at most alternate_shared of the excursions of angle `name` (those reaching min_ratio × its cycle
    amplitude cycle_deg, degrees) have a core that overlaps the core of one of the dominant angle's by more than
    alternate_overlap of the shorter core."""
    # its bumps neither make nor break the alternation; the cycle amplitude, not the median of its excursions,
    # which a few steps and as many bumps pull down to the bumps
    own = [ev for ev in events if ev.angles == (name,) and ev.amplitude >= params.min_ratio * cycle_deg]
    lead = [ev for ev in events if ev.angles == (dominant,)]
    if not own:
        return False
    own_se = np.array([ev.core for ev in own])  # (n, 2) frames
    lead_se = np.array([ev.core for ev in lead]).reshape(-1, 2)  # (m, 2) frames
    # (n, m) frames each own excursion shares with each lead one, as _shared
    frames = np.maximum(0, np.minimum(own_se[:, 1:], lead_se[:, 1]) - np.maximum(own_se[:, :1], lead_se[:, 0]))
    own_len = np.maximum(1, own_se[:, 1] - own_se[:, 0])
    lead_len = np.maximum(1, lead_se[:, 1] - lead_se[:, 0])
    shorter = np.minimum(own_len[:, None], lead_len[None, :])  # (n, m) frames
    shared = int(np.sum(np.any(frames > params.alternate_overlap * shorter, axis=1)))
    return shared <= params.alternate_shared * len(own)


def _repeating(
    t: np.ndarray, smoothed: dict[str, np.ndarray], found: dict[str, AngleExcursions], name: str, dominant: str | None
) -> list[RepEvent]:
    """Returns the excursions of angle `name`, none when it idles beside a repeating dominant angle: the dominant
    angle has a period P (duration / its cycles), `name` has none and its autocorrelation at lag P is below
    cycles.MIN_CORRELATION (the idle limb drifting or mistracked, not repeating the movement with a slow start)."""
    if name == dominant or dominant is None or found[dominant].n_cycles == 0 or found[name].n_cycles > 0:
        return found[name].events
    lag = int(round((t[-1] - t[0]) / found[dominant].n_cycles / series.frame_interval(t)))
    ac = cycles.autocorrelation(smoothed[name])
    return found[name].events if lag < ac.shape[0] and ac[lag] >= cycles.MIN_CORRELATION else []


def _peak_ordered(merged: list[RepEvent]) -> tuple[list[RepEvent], np.ndarray, np.ndarray]:
    """Returns (the events in the order of their peaks, (n,) peak frames, (n,) amplitudes in degrees)."""
    merged = sorted(merged, key=lambda ev: ev.peak)
    return merged, np.array([ev.peak for ev in merged]), np.array([ev.amplitude for ev in merged])


def _without(merged: list[RepEvent], drop: np.ndarray) -> list[RepEvent]:
    """Returns the events whose drop (n,) bool is False, in the order of their starts."""
    return sorted((ev for ev, gone in zip(merged, drop, strict=True) if not gone), key=lambda ev: ev.start)


def _drop_rebounds(merged: list[RepEvent], params: RepetitionParams) -> list[RepEvent]:
    """Drops the excursions that last less than shallow_duration × the median duration and peak within
    shallow_spacing × the median peak-to-peak spacing of a larger one or of one that lasts a repetition's time: a
    rebound, a split or a mistracked spike beside that one, not a repetition."""
    if len(merged) < 3:
        return merged
    merged, peaks, amplitude = _peak_ordered(merged)
    length = np.array([ev.end - ev.start for ev in merged])  # (n,) frames
    gap = np.diff(peaks)  # (n − 1,) frames
    room = params.shallow_spacing * float(np.median(gap))
    brief = length < params.shallow_duration * float(np.median(length))
    close_prev = np.concatenate(([False], (gap < room) & ((amplitude[:-1] > amplitude[1:]) | ~brief[:-1])))
    close_next = np.concatenate(((gap < room) & ((amplitude[1:] > amplitude[:-1]) | ~brief[1:]), [False]))
    return _without(merged, brief & (close_prev | close_next))


def _drop_off_cadence(merged: list[RepEvent], params: RepetitionParams, n_frames: int) -> list[RepEvent]:
    """Drops the shallow excursions (below min_ratio × the median amplitude) with no slot of the cadence of their
    own (a knee bump while standing between squats, or before the first): with room = shallow_spacing × the full
    repetitions' median peak-to-peak spacing, those between two full repetitions less than 2 × room apart, and
    those that peak within room of the full repetition on their one side and of that end of the recording
    (n_frames frames). A shallow repetition takes a slot of its own, a spacing away from at least one neighbour
    (UI-PRMD: a first lunge, a low leg raise)."""
    if len(merged) < 3:
        return merged
    merged, peaks, amplitude = _peak_ordered(merged)
    full = amplitude >= params.min_ratio * float(np.median(amplitude))
    full_peaks = peaks[full]
    if full_peaks.size < 3 or full.all():
        return sorted(merged, key=lambda ev: ev.start)
    room = params.shallow_spacing * float(np.median(np.diff(full_peaks)))
    k = np.searchsorted(full_peaks, peaks)  # the first full repetition peaking at or after each excursion
    edge0, edge1 = peaks, n_frames - 1 - peaks  # frames to the first and the last frame
    before = np.where(k > 0, peaks - full_peaks[np.maximum(k - 1, 0)], edge0)
    after = np.where(k < full_peaks.size, full_peaks[np.minimum(k, full_peaks.size - 1)] - peaks, edge1)
    inner = (k > 0) & (k < full_peaks.size)  # a full repetition on both sides, not an end of the recording
    squeezed = ((before < room) & (after < room)) | (inner & (before + after < 2 * room))
    return _without(merged, ~full & squeezed)


def _add_shallow(
    y: np.ndarray, name: str, rest: AngleExcursions, merged: list[RepEvent], params: RepetitionParams
) -> list[RepEvent]:
    """Adds the shallow repetitions of the dominant angle y: (T,) degrees, at rest at rest.rest_deg, that the
    hysteresis missed (module doc).

    In each stretch between counted repetitions (and before the first, after the last) at least shallow_duration ×
    their median duration long, the highest point of e = |y − rest end| at least shallow_spacing × the
    add_spacing_pct percentile of their peak-to-peak spacings from every counted peak is a repetition when e falls
    by add_rise_ratio × their median amplitude M on both sides of it, to minima (the stretch's before and after it)
    within add_levels_frac × M of each other (the rest may drift between repetitions), and its width at half its
    rise (frames) is at least shallow_duration × the median core of the counted ones (without add_half_width: its
    onset and return, the last frame before and the first after within onset_frac × M of those minima, are at least
    shallow_duration × the median duration apart).
    Half heights, not a level common to all: the bar and the candidate are then timed alike whatever their heights,
    and half a shallow rise stands clear of the noise at rest, which a tenth of it does not. Only the stretches and
    frames that can hold one are searched, as array operations (no second pass of the detector: 0.1 ms on a
    10-minute session).
    """
    if len(merged) < 3:
        return merged
    peaks = np.sort([ev.peak for ev in merged])  # (n,) frames
    room = params.shallow_spacing * float(np.percentile(np.diff(peaks), params.add_spacing_pct))
    amplitude = float(np.median([ev.amplitude for ev in merged]))
    duration = params.shallow_duration * float(np.median([ev.end - ev.start for ev in merged]))
    near = params.onset_frac * amplitude  # degrees: onset and return
    levels = params.add_levels_frac * amplitude  # degrees: the two sides' rest levels differ by at most this
    core = params.shallow_duration * float(np.median([ev.core[1] - ev.core[0] for ev in merged]))  # frames
    spans = np.array([(ev.start, ev.end) for ev in merged])  # (n, 2) frames, inclusive
    depth = np.zeros(y.shape[0] + 3, dtype=np.int64)  # counted repetitions over each frame, padded by one each side
    np.add.at(depth, spans[:, 0] + 1, 1)
    np.add.at(depth, spans[:, 1] + 2, -1)
    covered = np.cumsum(depth)[:-1] > 0
    covered[0] = covered[-1] = True
    stretches = np.flatnonzero(np.diff(covered)).reshape(-1, 2)  # (m, 2) [first, stop) frames between repetitions
    # a stretch holds no counted peak: its nearest are the last one before it and the first one after it
    k = np.searchsorted(peaks, stretches[:, 0])
    before = np.where(k > 0, peaks[np.maximum(k - 1, 0)] + room, -np.inf)
    after = np.where(k < peaks.size, peaks[np.minimum(k, peaks.size - 1)] - room, np.inf)
    first = np.maximum(stretches[:, 0], np.ceil(before)).astype(np.int64)  # (m,) the free frames: [first, last]
    last = np.minimum(stretches[:, 1] - 1, np.floor(after)).astype(np.int64)
    keep = (stretches[:, 1] - stretches[:, 0] >= duration) & (first <= last)
    extra: list[RepEvent] = []
    for (a, start), f0, f1 in zip(stretches[keep], first[keep], last[keep], strict=True):
        e = y[a:start] - rest.rest_deg if rest.rest_low else rest.rest_deg - y[a:start]
        p = f0 - a + int(np.argmax(e[f0 - a : f1 - a + 1]))
        base0, base1 = float(e[: p + 1].min()), float(e[p:].min())
        if e[p] - max(base0, base1) < params.add_rise_ratio * amplitude or abs(base0 - base1) > levels:
            continue
        rise = float(e[p] - 0.5 * (base0 + base1))
        onset = int(np.flatnonzero(e[: p + 1] <= base0 + near)[-1])
        back = p + int(np.flatnonzero(e[p:] <= base1 + near)[0])
        if (_half_width(e, p, rise) < core) if params.add_half_width else (back - onset < duration):
            continue
        extra.append(RepEvent(a + onset, a + p, a + back, rise, float(y[a + p]), side_of(name), (name,)))
    return sorted(merged + extra, key=lambda ev: ev.start) if extra else merged


def _half_width(e: np.ndarray, p: int, rise: float) -> int:
    """Returns the frames between the last frame before the peak p and the first after it where e: (T,) degrees is
    below e[p] − rise / 2 (e falls below that on both sides of p: the caller's rise test), minus one: the width at
    half its rise, as RepEvent.core measures a counted one."""
    half = e[p] - 0.5 * rise
    return int(np.flatnonzero(e[p:] < half)[0]) + int(p - np.flatnonzero(e[: p + 1] < half)[-1]) - 2


def count_repetitions(
    t: np.ndarray, angles: dict[str, np.ndarray], names: tuple[str, ...], params: RepetitionParams | None = None
) -> RepetitionResult:
    """Counts the repetitions of the defining angles `names` in angles {name: (T,) degrees} at times t: (T,) s.

    Raises ValueError naming an angle that is missing or whose shape differs from t.
    """
    params = params or RepetitionParams()
    t = np.asarray(t, dtype=np.float64)
    smoothed: dict[str, np.ndarray] = {}
    for name in names:
        if name not in angles:
            raise ValueError(f"angle {name!r} is missing; have {sorted(angles)}")
        smoothed[name] = series.smooth(t, np.asarray(angles[name], dtype=np.float64))
    # (p2, p98) of each smoothed angle, degrees: its range R (angle_range) and its two possible rest ends
    bounds = {n: tuple(np.percentile(y, [2.0, 98.0])) for n, y in smoothed.items() if y.size and np.isfinite(y).all()}
    ranges = {n: float(bounds[n][1] - bounds[n][0]) if n in bounds else 0.0 for n in smoothed}
    top = max(ranges.values(), default=0.0)
    moving = tuple(n for n in names if ranges[n] >= max(params.min_range_deg, params.side_ratio * top))
    found = {name: detect_angle(t, smoothed[name], name, params, bounds[name]) for name in moving}
    dominant = max(moving, key=lambda n: sum(ev.amplitude for ev in found[n].events)) if moving else None
    per_angle = {name: _repeating(t, smoothed, found, name, dominant) for name in moving}
    events = [ev for name in moving for ev in per_angle[name]]
    merged = merge_events(events, params.merge_overlap)
    counted = {
        n
        for n in moving
        if n == dominant or (dominant is not None and _alternates(n, dominant, events, params, found[n].cycle_deg))
    }
    merged = _drop_weak_lone(_keep_counted(merged, counted), params.lone_ratio)
    merged = _drop_off_cadence(_drop_rebounds(_drop_bumps(merged, params), params), params, t.shape[0])
    if dominant is not None:
        merged = _add_shallow(smoothed[dominant], dominant, found[dominant], merged, params)
    merged = [ev for ev in merged if ev.amplitude >= params.min_amplitude_deg]
    t0 = float(t[0]) if t.shape[0] else 0.0
    reps = [
        Repetition(
            index=i,
            start_s=float(t[ev.start] - t0),
            end_s=float(t[ev.end] - t0),
            duration_s=float(t[ev.end] - t[ev.start]),
            amplitude_deg=ev.amplitude,
            peak_deg=ev.peak_deg,
            side=ev.side,
            peak_s=float(t[ev.peak] - t0),
        )
        for i, ev in enumerate(merged)
    ]
    defining = dominant or (names[0] if names else None)
    return RepetitionResult(reps, defining, ranges, moving)
