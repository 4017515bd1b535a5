"""Leave-one-subject-out repetition counts on UI-PRMD s01-s05 (issue 24, point 4): how the counter's thresholds
generalise to a subject they were not chosen on.

The detector's thresholds (kinect_agent.analysis.repetitions.RepetitionParams) were developed on s01-s05, so the
counts of bench/repetitions.py on those subjects are counts on the tuning data. Here, for each subject in turn, the
thresholds are chosen on the other four from a grid around the defaults (the grid point with the most exact counts
over their correct and incorrect executions; ties go to the point nearest the defaults), then that subject's
recordings are counted with them. Prints per held-out subject and movement exact / off by one / off by more, the
thresholds each fold chose, and beside them the shipped defaults on the same recordings. Counted as
bench/repetitions.py counts (the raw recording's defining angles; --filtered: after the home agent's pipeline).

    python bench/repetitions_loso.py [--data ../shared/data] [--filtered] [--json OUT]
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:
    sys.path.insert(0, str(ROOT_DIR))

from backend.exercises.library import EXERCISES  # noqa: E402
from bench.repetitions import DEVELOPED_ON, KINDS, MOVEMENTS, TRUE_COUNT, subjects, summary  # noqa: E402
from kinect_agent.analysis.angles import counting_angles  # noqa: E402
from kinect_agent.analysis.repetitions import RepetitionParams, count_repetitions  # noqa: E402
from kinect_agent.formats import ui_prmd  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402

# the thresholds that decide most counts, each with values around its default (fractions of the angle's range)
GRID: dict[str, tuple[float, ...]] = {
    "enter_frac": (0.25, 0.3, 0.35),
    "exit_frac": (0.15, 0.2, 0.25),
    "lone_ratio": (0.5, 0.6, 0.7),
    "min_ratio": (0.3, 0.4, 0.5),
}


def recordings(data: Path, filtered: bool) -> list[dict]:
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


def grid_points() -> list[RepetitionParams]:
    """Returns every RepetitionParams of GRID (the other thresholds at their defaults)."""
    keys = list(GRID)
    return [
        replace(RepetitionParams(), **dict(zip(keys, values, strict=True)))
        for values in itertools.product(*GRID.values())
    ]


def _distance(p: RepetitionParams) -> float:
    default = RepetitionParams()
    return sum(abs(getattr(p, k) - getattr(default, k)) / getattr(default, k) for k in GRID)


def counts(recs: list[dict], params: RepetitionParams) -> np.ndarray:
    """Returns the count of each recording with params: (N,) int."""
    return np.array([len(count_repetitions(r["t"], r["angles"], r["names"], params).repetitions) for r in recs])


def loso(recs: list[dict]) -> tuple[list[dict], dict[str, dict]]:
    """Returns (rows: per recording its held-out count and the default count; per subject the thresholds chosen)."""
    points = grid_points()
    table = np.stack([counts(recs, p) for p in points])  # (P, N) counts per grid point and recording
    default = counts(recs, RepetitionParams())
    subject_of = np.array([r["subject"] for r in recs])
    rows, chosen = [], {}
    for held in sorted(set(subject_of)):
        train = subject_of != held
        exact = (table[:, train] == TRUE_COUNT).sum(axis=1)
        best = max(range(len(points)), key=lambda i: (exact[i], -_distance(points[i])))
        chosen[held] = {k: getattr(points[best], k) for k in GRID} | {"exact_on_the_four": int(exact[best])}
        for i in np.flatnonzero(~train):
            r = recs[i]
            rows.append({"kind": r["kind"], "subject": held, "movement": r["movement"],
                         "held_out": int(table[best, i]), "default": int(default[i])})  # fmt: skip
    return rows, chosen


def print_report(rows: list[dict], chosen: dict[str, dict]) -> None:
    """Prints the thresholds per fold, the cases not counted 10, then per kind: per subject and movement."""
    print("thresholds chosen on the other four subjects:")
    for subject, c in chosen.items():
        print(f"  without {subject}: " + ", ".join(f"{k} {v}" for k, v in c.items()))
    print("\ncases not counted 10 (held out | shipped defaults):")
    for r in rows:
        if r["held_out"] != TRUE_COUNT or r["default"] != TRUE_COUNT:
            print(f"  {r['kind']:<9} {r['subject']} {r['movement']}: {r['held_out']:>2} | {r['default']:>2}")
    for kind in KINDS:
        mine = [r for r in rows if r["kind"] == kind]
        print(f"\n{kind} executions: held out | shipped defaults")
        for key in ("subject", "movement"):
            for value in sorted({r[key] for r in mine}):
                part = [r for r in mine if r[key] == value]
                print(f"  {value}: {summary([r['held_out'] for r in part])} | {summary([r['default'] for r in part])}")
        print(f"  all: {summary([r['held_out'] for r in mine])} | {summary([r['default'] for r in mine])}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=ROOT_DIR.parent / "shared" / "data", help="the shared data")
    parser.add_argument("--filtered", action="store_true", help="count after the home agent's pipeline")
    parser.add_argument("--json", type=Path, help="also write the rows and the chosen thresholds to this file")
    args = parser.parse_args(argv)
    rows, chosen = loso(recordings(args.data, args.filtered))
    print_report(rows, chosen)
    if args.json:
        args.json.write_text(json.dumps({"rows": rows, "chosen": chosen, "grid": GRID,
                                         "defaults": asdict(RepetitionParams())}, indent=2))  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
