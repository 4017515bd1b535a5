"""Repetition counts on real Kinect v2 recordings of known length: UI-PRMD, s01-s05, correct and incorrect executions.

Each UI-PRMD episode (`mXX_sYY_eZZ_positions[_inc].txt.gz`) is one segmented repetition, so the ten episodes of a
movement and subject joined (kinect_agent.formats.ui_prmd.read_episodes) hold exactly ten. Counted as the server
counts them (kinect_agent.analysis.repetitions on the exercise's defining angles, backend.exercises.library), on the
raw recording and after the home agent's pipeline (kinect_agent.processing.pipeline.process, defaults). Prints every
case that is not 10, then per kind (correct, incorrect) and stage (raw, filtered): per movement, per subject and
overall, exact / off by one / off by more than one. Subjects: every one found in the folders (UI-PRMD has s01-s10;
subjects beyond s05 are held out from the detector's development and reported apart when present).

    python bench/repetitions.py [--data ../shared/data] [--no-filter] [--json OUT] [--set NAME=VALUE ...]

--set NAME=VALUE (repeatable) filters the UI-PRMD recordings with PipelineConfig overrides instead of the defaults.

Issue 13's target: at least 98 % exact and never off by more than one, on correct and incorrect executions alike.

With --simulated, simulated Kinect 2 sets of known length instead (kinect_agent.sources.simulator.simulate): every
simulated exercise × views --views (0° 30°) × --reps (5 10) repetitions × --seeds, counted as the server counts (the
recording's positions smoothed by series.smooth_positions, angles.counting_angles, count_repetitions) on the raw
skeletons and after the pipeline (process(...).filtered); --unsmoothed counts the angles of the positions as they
are, as the UI-PRMD count above does (the simulated numbers in bench/README.md before 2026-11-26 were measured so).
Prints every set not counted right, then exact / off by one / off by more per exercise, view, stage and seed, and
per stage and seed. --cache DIR keeps each set's raw and filtered positions (npz), so that a re-run after a change
to the counter does not filter again.

    python bench/repetitions.py --simulated [--seeds 301 302 303] [--views 0 30] [--reps 5 10] [--cache /tmp/npz]
                                [--unsmoothed] [--exercises squat side_step] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:  # `python bench/repetitions.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT_DIR))

from kinect_agent.analysis import series  # noqa: E402
from kinect_agent.analysis.angles import counting_angles  # noqa: E402
from kinect_agent.analysis.exercise import EXERCISES  # noqa: E402
from kinect_agent.analysis.repetitions import count_repetitions  # noqa: E402
from kinect_agent.formats import ui_prmd  # noqa: E402
from kinect_agent.processing.config import PipelineConfig  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402
from kinect_agent.sources.simulator import EXERCISES as SIMULATED  # noqa: E402
from kinect_agent.sources.simulator import simulate  # noqa: E402

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


def measure(data: Path, filtered: bool, config: PipelineConfig | None = None) -> list[dict[str, Any]]:
    """Returns one row per kind, movement and subject: the raw count and (filtered=True) the count after the
    pipeline (settings `config`, default the shipped ones)."""
    rows = []
    for kind, folder in KINDS.items():
        kinect = data / "ui-prmd" / folder / "Kinect"
        for subject in subjects(kinect):
            for movement in MOVEMENTS:
                rec = ui_prmd.read_episodes(kinect, movement=movement, subject=subject)
                row = {"kind": kind, "movement": movement, "subject": subject, "raw": count(rec, movement)}
                row["filtered"] = count(process(rec, config=config).filtered, movement) if filtered else None
                rows.append(row)
    return rows


def summary(counts: list[int]) -> str:
    """Returns "exact / off by one / off by more" of counts against TRUE_COUNT."""
    exact = sum(c == TRUE_COUNT for c in counts)
    one = sum(abs(c - TRUE_COUNT) == 1 for c in counts)
    return f"{exact}/{len(counts)} exact, {one} off by one, {len(counts) - exact - one} off by more"


def print_report(rows: list[dict[str, Any]]) -> None:
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


def count_simulated(t: np.ndarray, positions: np.ndarray, slug: str, smooth: bool = True) -> int:
    """Returns the count of positions: (T, J, 3) metres at t: (T,) s for the library exercise `slug`: as the server
    counts (kinect_agent.analysis.report.analyze_recording: positions smoothed by series.smooth_positions, counting
    angles, count_repetitions), or with smooth=False on the angles of the positions as they are (as count() above
    and the UI-PRMD test)."""
    names = EXERCISES[slug].defining_angles
    positions = series.smooth_positions(t, positions) if smooth else positions
    return len(count_repetitions(t, counting_angles(positions, names), names).repetitions)


def simulated_positions(
    slug: str, view: int, reps: int, seed: int, cache: Path | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Returns (t (T,) s, raw (T, J, 3) m, filtered (T, J, 3) m) of one simulated Kinect 2 set, from the cache when
    there."""
    path = cache / f"{slug}_v{view}_r{reps}_s{seed}.npz" if cache else None
    if path is not None and path.exists():
        z = np.load(path)
        return z["t"], z["raw"], z["filtered"]
    measured, _, _ = simulate(slug, reps, view_deg=view, seed=seed)
    filtered = process(measured).filtered.positions
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(path, t=measured.t, raw=measured.positions, filtered=filtered)
    return measured.t, measured.positions, filtered


def measure_simulated(
    seeds: list[int],
    views: list[int],
    reps: list[int],
    cache: Path | None,
    exercises: list[str] | None = None,
    smooth: bool = True,
) -> list[dict[str, Any]]:
    """Returns one row per exercise, view, repetitions and seed: the true count, raw and filtered counts
    (count_simulated with `smooth`)."""
    rows = []
    for slug in exercises or SIMULATED:
        for view in views:
            for n in reps:
                for seed in seeds:
                    t, raw, filtered = simulated_positions(slug, view, n, seed, cache)
                    rows.append({"exercise": slug, "view": view, "reps": n, "seed": seed,
                                 "raw": count_simulated(t, raw, slug, smooth),
                                 "filtered": count_simulated(t, filtered, slug, smooth)})  # fmt: skip
    return rows


def _tally(rows: list[dict[str, Any]], stage: str) -> str:
    """Returns "exact/n (±1 k, more m)" of the rows' counts at `stage` against their true count."""
    off = [abs(r[stage] - r["reps"]) for r in rows]
    return f"{sum(o == 0 for o in off)}/{len(off)} (±1 {sum(o == 1 for o in off)}, more {sum(o > 1 for o in off)})"


def print_simulated(rows: list[dict[str, Any]]) -> None:
    """Prints the sets not counted right, then per exercise, view, stage and seed, and per stage and seed."""
    seeds = sorted({r["seed"] for r in rows})
    print("simulated sets not counted right (true count: raw, filtered):")
    for r in rows:
        if r["raw"] != r["reps"] or r["filtered"] != r["reps"]:
            print(f"  {r['exercise']:<22} {r['view']:>2}° seed {r['seed']} {r['reps']:>2}: raw {r['raw']:>2}, "
                  f"filtered {r['filtered']:>2}")  # fmt: skip
    for stage in ("filtered", "raw"):
        print(f"\n{stage}: exact of the sets per exercise and view, counts per seed (5 reps | 10 reps)")
        print(f"  {'exercise':<22} view  " + "  ".join(f"seed {s:<15}" for s in seeds))
        for slug in dict.fromkeys(r["exercise"] for r in rows):
            for view in sorted({r["view"] for r in rows}):
                cells = []
                for s in seeds:
                    mine = [r for r in rows if r["exercise"] == slug and r["view"] == view and r["seed"] == s]
                    counts = " | ".join(f"{r[stage]:>2}" + ("" if r[stage] == r["reps"] else "*") for r in mine)
                    cells.append(f"{counts:<20}")
                print(f"  {slug:<22} {view:>3}°  " + "  ".join(cells))
        for s in seeds:
            print(f"  seed {s}: {_tally([r for r in rows if r['seed'] == s], stage)}")
        print(f"  all: {_tally(rows, stage)}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=ROOT_DIR.parent / "shared" / "data", help="the shared data")
    parser.add_argument("--no-filter", action="store_true", help="raw counts only (fast)")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="PipelineConfig override of the UI-PRMD filtering (repeatable)")  # fmt: skip
    parser.add_argument("--json", type=Path, help="also write every row to this file")
    parser.add_argument("--simulated", action="store_true", help="simulated sets instead of UI-PRMD")
    parser.add_argument("--seeds", type=int, nargs="+", default=[301, 302, 303], help="simulator seeds")
    parser.add_argument("--views", type=int, nargs="+", default=[0, 30], help="views, degrees")
    parser.add_argument("--reps", type=int, nargs="+", default=[5, 10], help="repetitions per set")
    parser.add_argument("--exercises", nargs="+", choices=SIMULATED, help="simulated exercises (default: all)")
    parser.add_argument("--cache", type=Path, help="folder keeping the simulated sets' positions (npz)")
    parser.add_argument("--unsmoothed", action="store_true",
                        help="count the angles of the positions as they are (the server smooths first)")  # fmt: skip
    args = parser.parse_args(argv)
    if args.simulated:
        started = time.perf_counter()
        rows = measure_simulated(args.seeds, args.views, args.reps, args.cache, args.exercises, not args.unsmoothed)
        print_simulated(rows)
        print(f"\n({time.perf_counter() - started:.0f} s)")
        if args.json:
            args.json.write_text(json.dumps(rows, indent=1))
        return 0
    if not (args.data / "ui-prmd").is_dir():
        print(f"error: {args.data / 'ui-prmd'} is missing", file=sys.stderr)
        return 2
    started = time.perf_counter()
    from bench.accuracy import pipeline_config

    rows = measure(args.data, filtered=not args.no_filter, config=pipeline_config(args.set))
    print_report(rows)
    print(f"\n({time.perf_counter() - started:.0f} s)")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
