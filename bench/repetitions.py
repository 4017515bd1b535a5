"""Repetition counts on real Kinect v2 recordings of known length: UI-PRMD, s01-s05, correct and incorrect executions.

Each UI-PRMD episode (`mXX_sYY_eZZ_positions[_inc].txt.gz`) is one segmented repetition, so the ten episodes of a
movement and subject joined (kinect_agent.formats.ui_prmd.read_episodes) hold exactly ten. Counted as the server
counts them (kinect_agent.analysis.repetitions on the exercise's defining angles, backend.exercises.library), on the
raw recording and after the home agent's pipeline (kinect_agent.processing.pipeline.process, defaults). Prints every
case that is not 10, then per kind (correct, incorrect) and stage (raw, filtered): per movement, per subject and
overall, exact / off by one / off by more than one. Subjects: every one found in the folders (UI-PRMD has s01-s10;
subjects beyond s05 are held out from the detector's development and reported apart when present).

    python bench/repetitions.py [--data ../shared/data] [--no-filter] [--json OUT]

Issue 13's target: at least 98 % exact and never off by more than one, on correct and incorrect executions alike.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:  # `python bench/repetitions.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT_DIR))

from backend.exercises.library import EXERCISES  # noqa: E402
from kinect_agent.analysis.angles import counting_angles  # noqa: E402
from kinect_agent.analysis.repetitions import count_repetitions  # noqa: E402
from kinect_agent.formats import ui_prmd  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402

KINDS = {"correct": "Segmented Movements", "incorrect": "Incorrect Segmented Movements"}
MOVEMENTS = [f"m{i:02d}" for i in range(1, 11)]
DEVELOPED_ON = {f"s{i:02d}" for i in range(1, 6)}  # the subjects the detector was tuned on
TRUE_COUNT = 10


def count(rec: Recording, movement: str) -> int:
    """Returns the server's repetition count of a UI-PRMD recording of `movement` ("m01")."""
    spec = next(s for s in EXERCISES.values() if s.uiprmd_movement == movement)
    names = spec.defining_angles
    return len(count_repetitions(rec.t, counting_angles(rec.positions, names), names).repetitions)


def subjects(folder: Path) -> list[str]:
    """Returns the subjects ("s01") with episodes in a UI-PRMD Kinect folder, sorted."""
    return sorted({name.split("_")[1] for name in (p.name for p in folder.rglob("m*_s*_e*_positions*"))})


def measure(data: Path, filtered: bool) -> list[dict]:
    """Returns one row per kind, movement and subject: the raw count and (filtered=True) the count after the
    pipeline."""
    rows = []
    for kind, folder in KINDS.items():
        kinect = data / "ui-prmd" / folder / "Kinect"
        for subject in subjects(kinect):
            for movement in MOVEMENTS:
                rec = ui_prmd.read_episodes(kinect, movement=movement, subject=subject)
                row = {"kind": kind, "movement": movement, "subject": subject, "raw": count(rec, movement)}
                row["filtered"] = count(process(rec).filtered, movement) if filtered else None
                rows.append(row)
    return rows


def summary(counts: list[int]) -> str:
    """Returns "exact / off by one / off by more" of counts against TRUE_COUNT."""
    exact = sum(c == TRUE_COUNT for c in counts)
    one = sum(abs(c - TRUE_COUNT) == 1 for c in counts)
    return f"{exact}/{len(counts)} exact, {one} off by one, {len(counts) - exact - one} off by more"


def print_report(rows: list[dict]) -> None:
    """Prints the cases that are not TRUE_COUNT, then the summaries per kind, stage, movement and subject."""
    stages = [s for s in ("raw", "filtered") if rows and rows[0][s] is not None]
    print("cases not counted 10:")
    for r in rows:
        if any(r[s] != TRUE_COUNT for s in stages):
            slug = next(s.slug for s in EXERCISES.values() if s.uiprmd_movement == r["movement"])
            print(f"  {r['kind']:<9} {r['movement']} {r['subject']} {slug:<36} " +
                  "  ".join(f"{s} {r[s]}" for s in stages))  # fmt: skip
    for held_out in (False, True):
        for kind in KINDS:
            mine = [r for r in rows if r["kind"] == kind and (r["subject"] not in DEVELOPED_ON) == held_out]
            if not mine:
                continue
            print(f"\n{kind} executions" + (" (held-out subjects)" if held_out else ""))
            for key in ("movement", "subject"):
                for value in sorted({r[key] for r in mine}):
                    part = [r for r in mine if r[key] == value]
                    print(f"  {value}: " + "; ".join(f"{s} {summary([r[s] for r in part])}" for s in stages))
            print("  all: " + "; ".join(f"{s} {summary([r[s] for r in mine])}" for s in stages))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=ROOT_DIR.parent / "shared" / "data", help="the shared data")
    parser.add_argument("--no-filter", action="store_true", help="raw counts only (fast)")
    parser.add_argument("--json", type=Path, help="also write every row to this file")
    args = parser.parse_args(argv)
    if not (args.data / "ui-prmd").is_dir():
        print(f"error: {args.data / 'ui-prmd'} is missing", file=sys.stderr)
        return 2
    started = time.perf_counter()
    rows = measure(args.data, filtered=not args.no_filter)
    print_report(rows)
    print(f"\n({time.perf_counter() - started:.0f} s)")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
