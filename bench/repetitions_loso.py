"""Leave-one-subject-out repetition counts on UI-PRMD s01-s05 (issue 24, point 4): how the counter's thresholds
generalise to a subject they were not chosen on.

The detector's thresholds (kinect_agent.analysis.repetitions.RepetitionParams) were developed on s01-s05, so the
counts of bench/repetitions.py on those subjects are counts on the tuning data. Here, for each subject in turn, the
thresholds are chosen on the other four from a grid around the defaults (the grid point with the most exact counts
over their correct and incorrect executions; ties go to the point nearest the defaults), then that subject's
recordings are counted with them. Prints per held-out subject and movement exact / off by one / off by more, the
thresholds each fold chose, and beside them the shipped defaults on the same recordings. Counted as
bench/repetitions.py counts (the raw recording's defining angles; --filtered: after the home agent's pipeline).

--rules: the grid is RULE_GRID instead (the rules of issue 24 point 4 on or off: a shallow excursion kept for a
cadence slot of its own, the spacing percentile of the added shallow repetitions, an added one timed by its width at
half its own rise), ties going to the rules as they were before (RULE_BEFORE). --mixes N adds, per subject and movement,
N recordings of 10 episodes drawn without replacement from that subject's 10 correct and 10 incorrect ones (seeded;
--mix-seed K draws another N): new sessions of the same people, with correct and incorrect repetitions mixed as a
patient mixes them, each exactly 10 repetitions; they are reported apart (kind "mixed") and count in the choice on
the four subjects.

    python bench/repetitions_loso.py [--data ../shared/data] [--filtered] [--rules] [--mixes 20] [--mix-seed 0]
                                     [--json OUT]
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
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
# the counter before those rules
RULE_BEFORE = RepetitionParams(slot_keeps_shallow=False, add_spacing_pct=50.0, add_half_width=False)


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


def mixes(data: Path, n: int, filtered: bool, seed: int = 0) -> list[dict[str, Any]]:
    """Returns, per subject (s01-s05) and movement, n entries like recordings()'s (kind "mixed"): 10 episodes drawn
    without replacement from the subject's 10 correct and 10 incorrect ones (seed from subject, movement and `seed`;
    seed 0 draws the mixes of 2026-11-27)."""
    out = []
    for subject in sorted(DEVELOPED_ON):
        for movement in MOVEMENTS:
            parts = []
            for folder in KINDS.values():
                files = (data / "ui-prmd" / folder / "Kinect").rglob(f"{movement}_{subject}_e*_positions*")
                parts += [ui_prmd.read_episode(path) for path in sorted(files)]
            rng = np.random.default_rng(1000 * int(subject[1:]) + int(movement[1:]) + 100_000 * seed)
            names = next(s for s in EXERCISES.values() if s.uiprmd_movement == movement).defining_angles
            for _ in range(n):
                rec = Recording.concatenate([parts[k] for k in rng.choice(len(parts), TRUE_COUNT, replace=False)])
                rec = process(rec).filtered if filtered else rec
                out.append({"kind": "mixed", "subject": subject, "movement": movement, "t": rec.t, "names": names,
                            "angles": counting_angles(rec.positions, names)})  # fmt: skip
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
    parser.add_argument("--json", type=Path, help="also write the rows and the chosen thresholds to this file")
    args = parser.parse_args(argv)
    grid, reference = (RULE_GRID, RULE_BEFORE) if args.rules else (GRID, RepetitionParams())
    recs = recordings(args.data, args.filtered) + mixes(args.data, args.mixes, args.filtered, args.mix_seed)
    rows, chosen = loso(recs, grid, reference)
    print_report(rows, chosen)
    if args.json:
        args.json.write_text(json.dumps({"rows": rows, "chosen": chosen, "grid": grid,
                                         "defaults": asdict(RepetitionParams())}, indent=2))  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
