"""Leave-one-subject-out repetition counts on UI-PRMD s01-s05 (issue 24, point 4): how the counter's thresholds
generalise to a subject they were not chosen on.

The detector's thresholds (kinect_agent.analysis.repetitions.RepetitionParams) were developed on s01-s05, so the
counts of bench/repetitions.py on those subjects are counts on the tuning data. Here, for each subject in turn, the
thresholds are chosen on the other four from a grid around the defaults (the grid point with the most exact counts
over their correct and incorrect executions; ties go to the point nearest the defaults), then that subject's
recordings are counted with them. Prints per held-out subject and movement exact / off by one / off by more, the
thresholds each fold chose, and beside them the shipped defaults on the same recordings. Counted as
bench/repetitions.py counts (the raw recording's defining angles; --filtered: after the home agent's pipeline).

--add-rules: the grid is ADD_GRID (the two tests of an added shallow repetition: its rise, add_rise_ratio × M, and
how far apart the rest levels on its two sides may be, add_levels_frac × M), ties to ADD_BEFORE.
--rules: the grid is RULE_GRID instead (the rules of issue 24 point 4 on or off: a shallow excursion kept for a
cadence slot of its own, the spacing percentile of the added shallow repetitions, an added one timed by its width at
half its own rise), ties going to the rules as they were before (RULE_BEFORE). --mixes N adds, per subject and movement,
N recordings of 10 episodes drawn without replacement from that subject's 10 correct and 10 incorrect ones (seeded;
--mix-seed K draws another N): new sessions of the same people, with correct and incorrect repetitions mixed as a
patient mixes them, each exactly 10 repetitions; they are reported apart (kind "mixed") and count in the choice on
the four subjects. --join chain joins the same drawn episodes as a chain_order (each next one the episode that
begins nearest where the one before ends, from where the subject's takes begin) instead of in the order drawn: the
real recordings' consecutive episodes continue each other (junction jumps p50 1.0°, p90 4.1°), episodes of two takes
joined at random do not (p50 3.7°, p90 16.8°); both are printed.

    python bench/repetitions_loso.py [--data ../shared/data] [--filtered] [--rules | --add-rules] [--mixes 20]
                                     [--mix-seed 0] [--join shuffled|chain] [--json OUT]
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import warnings
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:
    sys.path.insert(0, str(ROOT_DIR))

from bench.repetitions import DEVELOPED_ON, KINDS, MOVEMENTS, TRUE_COUNT, subjects, summary  # noqa: E402
from kinect_agent.analysis.angles import counting_angles  # noqa: E402
from kinect_agent.analysis.exercise import EXERCISES  # noqa: E402
from kinect_agent.analysis.repetitions import RepetitionParams, count_repetitions  # noqa: E402
from kinect_agent.formats import ui_prmd  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402

# the thresholds that decide most counts, each with values around its default (fractions of the angle's range)
GRID: dict[str, tuple[float, ...]] = {
    "enter_frac": (0.25, 0.3, 0.35),
    "exit_frac": (0.15, 0.2, 0.25),
    "lone_ratio": (0.5, 0.6, 0.7),
    "min_ratio": (0.3, 0.4, 0.5),
}
# --rules: the rules added for issue 24 point 4, on and off
RULE_GRID: dict[str, tuple[float, ...]] = {
    "slot_keeps_shallow": (False, True),
    "add_spacing_pct": (50.0, 33.0, 25.0),
    "add_half_width": (False, True),
}
# --add-rules: the two tests of _add_shallow (the rise, the one rest level), the other rules as shipped
ADD_GRID: dict[str, tuple[float, ...]] = {
    "add_rise_ratio": (0.2, 0.15, 0.1),
    "add_levels_frac": (0.1, 0.2, 0.3),
}
END_FRAMES = 5  # frames at each end of an episode whose median is its first / last value (_ends)
# the counter before those rules
RULE_BEFORE = RepetitionParams(slot_keeps_shallow=False, add_spacing_pct=50.0, add_half_width=False)
# the added repetition's tests as they were before ADD_GRID
ADD_BEFORE = RepetitionParams(add_rise_ratio=0.2, add_levels_frac=0.1)


def recordings(data: Path, filtered: bool) -> list[dict[str, Any]]:
    """Returns one entry per kind, subject (s01-s05) and movement: t (T,) s and the defining angles {name: (T,)
    degrees} of the joined episodes (ten repetitions), raw or after the pipeline."""
    out = []
    for kind, folder in KINDS.items():
        kinect = data / "ui-prmd" / folder / "Kinect"
        for subject in (s for s in subjects(kinect) if s in DEVELOPED_ON):
            for movement in MOVEMENTS:
                rec = ui_prmd.read_episodes(kinect, movement=movement, subject=subject)
                rec = process(rec).filtered if filtered else rec
                names = next(s for s in EXERCISES.values() if s.uiprmd_movement == movement).defining_angles
                out.append({"kind": kind, "subject": subject, "movement": movement, "t": rec.t, "names": names,
                            "angles": counting_angles(rec.positions, names)})  # fmt: skip
    return out


def _ends(rec: Recording, names: tuple[str, ...]) -> np.ndarray:
    """Returns (2, A) degrees: the median of the first and of the last END_FRAMES frames of each defining angle."""
    angles = counting_angles(rec.positions, names)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an angle untracked at an end: NaN, ignored by _jump
        return np.array([[np.nanmedian(angles[n][sl]) for n in names]
                         for sl in (slice(0, END_FRAMES), slice(-END_FRAMES, None))])  # fmt: skip


def _jump(before: np.ndarray, after: np.ndarray) -> float:
    """Returns the largest |after − before| over the angles (A,) degrees where both are known, 0.0 where none is."""
    d = np.abs(np.asarray(after) - np.asarray(before))
    return float(np.nanmax(d)) if np.isfinite(d).any() else 0.0


def chain_order(drawn: list[int], ends: list[np.ndarray], start: np.ndarray) -> list[int]:
    """Returns the drawn episodes (indices into ends: (2, A) first and last values each) as a nearest-end chain: from
    the posture the subject's takes begin in (start: (A,) degrees), each next episode the one whose first values are
    nearest the last values of the one before (largest angle difference; ties to the order drawn)."""
    left, order, here = list(drawn), [], start
    while left:
        nxt = min(left, key=lambda k: _jump(here, ends[k][0]))
        order.append(nxt)
        left.remove(nxt)
        here = ends[nxt][1]
    return order


def mixes(data: Path, n: int, filtered: bool, seed: int = 0, join: str = "shuffled") -> list[dict[str, Any]]:
    """Returns, per subject (s01-s05) and movement, n entries like recordings()'s (kind "mixed"): 10 episodes drawn
    without replacement from the subject's 10 correct and 10 incorrect ones (seed from subject, movement and `seed`;
    seed 0 draws the mixes of 2026-11-27), joined in the order drawn (join "shuffled", as on 2026-11-27) or as a
    chain_order (join "chain": the same episodes, each next one beginning where the one before ends, as consecutive
    episodes of a real take do). Each entry also has "jumps": the largest defining-angle jump at each junction
    (degrees, _jump of the last and first END_FRAMES frames' medians)."""
    out = []
    for subject in sorted(DEVELOPED_ON):
        for movement in MOVEMENTS:
            parts = []
            for folder in KINDS.values():
                files = (data / "ui-prmd" / folder / "Kinect").rglob(f"{movement}_{subject}_e*_positions*")
                parts += [ui_prmd.read_episode(path) for path in sorted(files)]
            rng = np.random.default_rng(1000 * int(subject[1:]) + int(movement[1:]) + 100_000 * seed)
            names = next(s for s in EXERCISES.values() if s.uiprmd_movement == movement).defining_angles
            ends = [_ends(part, names) for part in parts]
            # where the subject's two takes begin: the first values of each take's first episode, averaged
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # an angle untracked at both: NaN, ignored by _jump
                start = np.nanmean([ends[0][0], ends[len(parts) // 2][0]], axis=0)
            for _ in range(n):
                order = [int(k) for k in rng.choice(len(parts), TRUE_COUNT, replace=False)]
                order = chain_order(order, ends, start) if join == "chain" else order
                rec = Recording.concatenate([parts[k] for k in order])
                rec = process(rec).filtered if filtered else rec
                jumps = [_jump(ends[a][1], ends[b][0]) for a, b in itertools.pairwise(order)]
                out.append({"kind": "mixed", "subject": subject, "movement": movement, "t": rec.t, "names": names,
                            "angles": counting_angles(rec.positions, names), "jumps": jumps})  # fmt: skip
    return out


def real_jumps(data: Path) -> list[float]:
    """Returns the largest defining-angle jump (degrees) at every junction of the real recordings: each kind's
    consecutive episodes e01-e10 of s01-s05, as recordings() joins them."""
    out = []
    for folder in KINDS.values():
        kinect = data / "ui-prmd" / folder / "Kinect"
        for subject in sorted(DEVELOPED_ON):
            for movement in MOVEMENTS:
                names = next(s for s in EXERCISES.values() if s.uiprmd_movement == movement).defining_angles
                files = sorted(kinect.rglob(f"{movement}_{subject}_e*_positions*"))
                ends = [_ends(ui_prmd.read_episode(path), names) for path in files]
                out += [_jump(a[1], b[0]) for a, b in itertools.pairwise(ends)]
    return out


def grid_points(grid: dict[str, tuple[float, ...]]) -> list[RepetitionParams]:
    """Returns every RepetitionParams of grid (the other thresholds at their defaults)."""
    keys = list(grid)
    return [
        # the defaults with this point's values (an unknown name raises TypeError, as in dataclasses.replace)
        RepetitionParams(**(asdict(RepetitionParams()) | dict(zip(keys, values, strict=True))))
        for values in itertools.product(*grid.values())
    ]


def _distance(p: RepetitionParams, grid: dict[str, tuple[float, ...]], reference: RepetitionParams) -> float:
    return sum(abs(float(getattr(p, k)) - float(getattr(reference, k))) / max(abs(float(getattr(reference, k))), 1.0)
               for k in grid)  # fmt: skip


def counts(recs: list[dict[str, Any]], params: RepetitionParams) -> np.ndarray:
    """Returns the count of each recording with params: (N,) int."""
    return np.array([len(count_repetitions(r["t"], r["angles"], r["names"], params).repetitions) for r in recs])


def loso(
    recs: list[dict[str, Any]], grid: dict[str, tuple[float, ...]], reference: RepetitionParams
) -> tuple[list[dict[str, Any]], dict[str, dict[str, Any]]]:
    """Returns (rows: per recording its held-out count, the default count and the reference's; per subject the
    settings chosen on the other four: most exact counts there, ties to the point nearest `reference`)."""
    points = grid_points(grid)
    table = np.stack([counts(recs, p) for p in points])  # (P, N) counts per grid point and recording
    default, before = counts(recs, RepetitionParams()), counts(recs, reference)
    subject_of = np.array([r["subject"] for r in recs])
    rows, chosen = [], {}
    for held in sorted(set(subject_of)):
        train = subject_of != held
        exact = (table[:, train] == TRUE_COUNT).sum(axis=1)
        best = max(range(len(points)), key=lambda i: (exact[i], -_distance(points[i], grid, reference)))
        chosen[held] = {k: getattr(points[best], k) for k in grid} | {"exact_on_the_four": int(exact[best])}
        for i in np.flatnonzero(~train):
            r = recs[i]
            rows.append({"kind": r["kind"], "subject": held, "movement": r["movement"], "held_out": int(table[best, i]),
                         "default": int(default[i]), "before": int(before[i])})  # fmt: skip
    return rows, chosen


def print_report(rows: list[dict[str, Any]], chosen: dict[str, dict[str, Any]]) -> None:
    """Prints the settings per fold, the cases not counted 10, then per kind: per subject and movement."""
    print("settings chosen on the other four subjects:")
    for subject, c in chosen.items():
        print(f"  without {subject}: " + ", ".join(f"{k} {v}" for k, v in c.items()))
    print("\nrecordings (not mixes) not counted 10 (held out | shipped defaults | reference):")
    for r in rows:
        if r["kind"] != "mixed" and {r["held_out"], r["default"], r["before"]} != {TRUE_COUNT}:
            print(f"  {r['kind']:<9} {r['subject']} {r['movement']}: {r['held_out']:>2} | {r['default']:>2} | "
                  f"{r['before']:>2}")  # fmt: skip
    for kind in dict.fromkeys(r["kind"] for r in rows):
        mine = [r for r in rows if r["kind"] == kind]
        print(f"\n{kind} executions: held out | shipped defaults | reference")
        for key in ("subject", "movement"):
            for value in sorted({r[key] for r in mine}):
                part = [r for r in mine if r[key] == value]
                print(
                    f"  {value}: "
                    + " | ".join(summary([r[c] for r in part]) for c in ("held_out", "default", "before"))
                )
        print("  all: " + " | ".join(summary([r[c] for r in mine]) for c in ("held_out", "default", "before")))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=ROOT_DIR.parent / "shared" / "data", help="the shared data")
    parser.add_argument("--filtered", action="store_true", help="count after the home agent's pipeline")
    parser.add_argument("--rules", action="store_true", help="choose among RULE_GRID instead of GRID")
    parser.add_argument("--mixes", type=int, default=0, help="episode mixes per subject and movement (0: none)")
    parser.add_argument("--mix-seed", type=int, default=0, help="which draw of the mixes (0: those of 2026-11-27)")
    parser.add_argument(
        "--join",
        choices=("shuffled", "chain"),
        default="shuffled",
        help="mixes joined in the order drawn, or each episode next to the one it continues best",
    )
    parser.add_argument("--add-rules", action="store_true", help="choose among ADD_GRID (the shipped rules otherwise)")
    parser.add_argument("--json", type=Path, help="also write the rows and the chosen thresholds to this file")
    args = parser.parse_args(argv)
    grid, reference = (RULE_GRID, RULE_BEFORE) if args.rules else (GRID, RepetitionParams())
    grid, reference = (ADD_GRID, ADD_BEFORE) if args.add_rules else (grid, reference)
    mixed = mixes(args.data, args.mixes, args.filtered, args.mix_seed, args.join)
    rows, chosen = loso(recordings(args.data, args.filtered) + mixed, grid, reference)
    print_report(rows, chosen)
    if mixed:
        real, joined = real_jumps(args.data), [j for r in mixed for j in r["jumps"]]
        print("\nlargest defining-angle jump at each junction, degrees, p50 / p90 / p99 / max:")
        for label, jumps in (("real recordings (consecutive episodes)", real), (f"mixes ({args.join})", joined)):
            print(f"  {label}: " + " / ".join(f"{v:.1f}" for v in np.percentile(jumps, [50, 90, 99, 100])))
    if args.json:
        args.json.write_text(json.dumps({"rows": rows, "chosen": chosen, "grid": grid,
                                         "defaults": asdict(RepetitionParams())}, indent=2))  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
