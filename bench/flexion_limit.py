"""How far hip and shoulder flexion reach on mocap truth and on the Kinect, and what a flexion limit would withhold
(issue 24.1; kinect_agent.analysis.anatomy.FLEXION_LIMIT_DEG).

Angles as kinect_agent.body.angles defines them: the thigh (KNE-HIP) or upper arm (ELB-SHO) in the trunk's sagittal
plane, atan2(fwd, down), wrapped into [-100, 260), NaN more than 60° off the plane. Per recording and angle (both
sides), on the raw positions smoothed as the server smooths them (series.smooth_positions, mocap thinned to 30 Hz,
bench/flexion_seam.recordings: UI-PRMD Kinect s01-s05 and Vicon s01, correct and incorrect, KERAAL Kinect and Vicon,
HDM05 bd/bk per class, CMU 13_29, UTKinect s01-s05):
    top     the highest value of any frame (what a repetition's check reads, anatomy.repetition_beyond_anatomy)
    p99     the range of motion's upper end (range_of_motion: 99th percentile; intervals.beyond_anatomy)
Printed: the highest top and p99 per source, the mocap recordings' tops in order, and per candidate limit the
recordings (angle-recordings, both sides) whose top / p99 pass it, per source and movement.

With --agent, the agent's path instead (capture.make_payload: filter, session file; report.analyze_recording, the
shipped limits): per source and movement, the recordings whose range of motion of each flexion is withheld for
beyond_anatomy, the repetitions withheld and the sessions' range of motion withheld, by the joint whose limit
withholds them (whole recordings, UI-PRMD Kinect and Vicon, KERAAL, HDM05, CMU).

    python bench/flexion_limit.py [--data ../shared/data] [--sources uiprmd,vicon,keraal,hdm05,cmu,utkinect]
                                  [--agent] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:
    sys.path.insert(0, str(ROOT_DIR))

from bench.flexion_seam import recordings  # noqa: E402
from kinect_agent.analysis import series  # noqa: E402
from kinect_agent.analysis.anatomy import HIP_LIMIT_DEG, KNEE_ELBOW_LIMIT_DEG  # noqa: E402
from kinect_agent.analysis.angles import measured_angles  # noqa: E402
from kinect_agent.analysis.exercise import EXERCISES  # noqa: E402
from kinect_agent.analysis.range_of_motion import range_of_motion  # noqa: E402
from kinect_agent.analysis.report import analyze_recording  # noqa: E402
from kinect_agent.body.angles import joint_angles  # noqa: E402
from kinect_agent.capture import make_payload  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402

NAMES = ("hip_flexion_L", "hip_flexion_R", "shoulder_flexion_L", "shoulder_flexion_R")
CANDIDATES = (170.0, 180.0, 190.0, 200.0, 210.0, 220.0)  # degrees
MOCAP = ("ui-prmd vicon", "hdm05", "cmu", "keraal vicon")
LIMITS = {"hip": HIP_LIMIT_DEG, "knee or elbow": KNEE_ELBOW_LIMIT_DEG}  # a withheld repetition's joint by its limit
DEFAULT_SLUG = {"keraal": "squat", "hdm05": "hurdle_step", "cmu": "squat", "utkinect": "shoulder_flexion"}


def source_of(source: str, label: str) -> str:
    """Returns the source with KERAAL split into its Kinect and Vicon recordings."""
    if source == "keraal":
        return "keraal vicon" if "Vicon" in label else "keraal kinect"
    return source


def movement_of(source: str, label: str) -> str:
    """Returns the movement a recording shows: UI-PRMD's m01-m10 and kind, HDM05's class, else the source."""
    if source.startswith("ui-prmd"):
        movement, _, kind = label.split()
        return f"{movement} {kind}"
    if source == "hdm05":
        return label.split()[0]
    return source


def tops(rec: Recording) -> dict[str, dict[str, float | None]]:
    """Returns {angle: {"top", "p99"}} degrees (None where never defined) of the smoothed raw positions."""
    smoothed = series.smooth_positions(rec.t, rec.positions)
    angles = joint_angles(smoothed)
    rom = range_of_motion(rec.t, {n: angles[n] for n in NAMES}, presmoothed=True)
    out: dict[str, dict[str, float | None]] = {}
    for name in NAMES:
        x = angles[name]
        out[name] = {"top": float(np.nanmax(x)) if np.isfinite(x).any() else None, "p99": rom[name]["max_deg"]}
    return out


def agent(rec: Recording, slug: str) -> dict[str, Any]:
    """Returns what the agent's path withholds for beyond_anatomy on one recording of exercise `slug`, and the
    highest value ("top") and range of motion's upper end ("p99") of each flexion it measured (degrees)."""
    payload = make_payload(rec, session_id="00000000-0000-4000-8000-000000000001", created_at="2026-11-28T00:00:00Z")
    assert payload.filtered is not None
    doc = analyze_recording(payload.raw, EXERCISES[slug], filtered=payload.filtered, angle_sd=payload.angle_sd)
    measured = measured_angles(rec.t, payload.filtered.positions).angles
    withheld = doc.range_of_motion_withheld or {}
    reps = doc.repetition_list
    rom = range_of_motion(rec.t, {n: measured[n] for n in NAMES}, presmoothed=True)
    return {
        "rom": {
            n: float(withheld[n].params["reached"])
            for n in NAMES
            if n in withheld and withheld[n].id == "beyond_anatomy"
        },  # fmt: skip
        "tops": {n: float(np.nanmax(measured[n])) if np.isfinite(measured[n]).any() else None for n in NAMES},
        "p99": {n: rom[n]["max_deg"] for n in NAMES},
        "reps": len(reps),
        "reps_withheld": {
            joint: sum(r.withheld is not None and r.withheld.params["limit"] == round(limit) for r in reps)
            for joint, limit in LIMITS.items()
        },  # fmt: skip
        "rom_deg_withheld": next(
            (
                joint
                for joint, limit in LIMITS.items()
                if doc.rom_deg_withheld is not None and doc.rom_deg_withheld.params["limit"] == round(limit)
            ),
            None,
        ),  # fmt: skip
    }


def print_tops(rows: list[dict[str, Any]]) -> None:
    """Prints per source the highest top and p99, the mocap tops, and per candidate the recordings past it."""
    for source in dict.fromkeys(r["source"] for r in rows):
        mine = [r for r in rows if r["source"] == source]
        for prefix in ("hip_flexion", "shoulder_flexion"):
            vals = [(r[n]["top"], r[n]["p99"], r["label"], n[-1]) for r in mine for n in NAMES if n.startswith(prefix)]
            vals = [v for v in vals if v[0] is not None]
            best = max(vals, key=lambda v: v[0])
            print(f"{source:<14} {prefix:<17} top {best[0]:6.1f} ({best[2]} {best[3]})  "
                  f"p99 max {max(v[1] for v in vals if v[1] is not None):6.1f}")  # fmt: skip
            if source in MOCAP:
                ordered = sorted(vals, key=lambda v: -v[0])[:6]
                print("      highest: " + ", ".join(f"{v[2]} {v[3]} {v[0]:.1f}/{v[1]:.1f}" for v in ordered))
    for prefix in ("hip_flexion", "shoulder_flexion"):
        print(f"\n{prefix}: angle-recordings (both sides) whose top / p99 pass each candidate, per source and movement")
        groups: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
        for r in rows:
            groups[(r["source"], r["movement"])].append(r)
        for (source, movement), mine in groups.items():
            cells = []
            for limit in CANDIDATES:
                top = sum((r[n]["top"] or -1e9) > limit for r in mine for n in NAMES if n.startswith(prefix))
                p99 = sum((r[n]["p99"] or -1e9) > limit for r in mine for n in NAMES if n.startswith(prefix))
                cells.append(f"{limit:.0f}: {top:>2}/{p99:<2}")
            print(f"  {source:<14} {movement:<26} ({2 * len(mine):>3})  " + "  ".join(cells))


def print_agent(rows: list[dict[str, Any]]) -> None:
    """Prints per source and movement the recordings whose flexion ranges and repetitions are withheld."""
    groups: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
    for r in rows:
        groups[(r["source"], r["movement"])].append(r)
    for (source, movement), mine in groups.items():
        ranges = {p: sum(n.startswith(p) for r in mine for n in r["rom"]) for p in ("hip", "shoulder")}
        recs = sum(bool(r["rom"]) for r in mine)
        reps = " + ".join(f"{sum(r['reps_withheld'][j] for r in mine)} ({j})" for j in LIMITS)
        roms = " + ".join(f"{sum(r['rom_deg_withheld'] == j for r in mine)} ({j})" for j in LIMITS)
        print(f"  {source:<14} {movement:<26} recordings {len(mine):>2}: ranges withheld in {recs:>2} (hip "
              f"{ranges['hip']}, shoulder {ranges['shoulder']}), repetitions withheld {reps} of "
              f"{sum(r['reps'] for r in mine)}, session range withheld in {roms}")  # fmt: skip
        top = max(
            (v for r in mine for n, v in r["tops"].items() if v is not None and n.startswith("hip")),
            default=float("nan"),
        )
        print(f"      hip flexion, highest filtered frame {top:.1f}")
        for r in mine:
            if r["rom"]:
                print(f"      {r['label']}: " + ", ".join(f"{n} {v:.0f}" for n, v in r["rom"].items()))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=ROOT_DIR.parent / "shared" / "data")
    parser.add_argument("--sources", default="uiprmd,vicon,keraal,hdm05,cmu,utkinect")
    parser.add_argument("--agent", action="store_true")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    started = time.perf_counter()
    rows = []
    for raw_source, label, slug, rec in recordings(args.data, set(args.sources.split(","))):
        source = source_of(raw_source, label)
        row: dict[str, Any] = {"source": source, "movement": movement_of(source, label), "label": label}
        if args.agent:
            row |= agent(rec, slug or DEFAULT_SLUG[raw_source])
        else:
            row |= tops(rec)
        rows.append(row)
    (print_agent if args.agent else print_tops)(rows)
    print(f"\n{len(rows)} recordings in {time.perf_counter() - started:.0f} s")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
