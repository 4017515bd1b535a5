"""Where the sagittal-plane angles (shoulder flexion, hip flexion) are ill-conditioned or cross their seam on real and
simulated recordings, and whether that reaches the counts or the ranges of motion (issue 24, points 1 and 4).

The planar angle atan2(fwd, down) of a limb (kinect_agent.body.angles._plane_angle) is singular where the limb points
along the plane's normal (the arm or thigh straight out to the side), wrapped at a seam (SAGITTAL_SEAM_DEG, −100/260
since 2026-11-28; −120/240 before), and masked (NaN) more than 60° out of its plane; the counter reads the
shoulder flexion unmasked (counting_angles) and the hips as the thigh's signed elevation (continuous). Per recording
and angle (both sides), on the raw positions smoothed as the server smooths them (series.smooth_positions):
    off≥60     % of tracked frames where the limb is ≥ 60° out of the sagittal plane (measured angle NaN there)
    off≥80     % of frames ≥ 80° out (the unmasked angle's sensitivity to the limb's direction ≥ 5.8×)
    sector     % of frames whose unmasked angle reads a value no sagittal movement reaches (shoulder > 200° or
               < −90°; hip > 150° or < −60°), and of those the share the mask leaves defined (masked-in)
    jumps      frames where the counter's signal steps by more than JUMP_DEG in one frame (shoulder: the unmasked
               planar angle; hip: the signed thigh elevation), and where the measured angle steps so between two
               consecutive defined frames (the curve on the session page, the range of motion)
    rom        the measured angle's range of motion (range_of_motion: 1st-99th percentiles of the defined frames)
    back       frames with the limb within 60° of the plane (defined) per 15° sector behind the trunk, −135..−60°
               (= 225..300°): where a seam leaves fewest frames on its far side
    seams      per seam candidate (SEAMS, the measured angle wrapped there): the recordings whose measured curve steps
               by more than 180° between consecutive defined frames (crosses the seam), those whose range of
               motion is wider than 300° (a range spanning the seam, shown as nearly a whole turn), and the share of
               frames within 15° of the seam
Where the angle defines the exercise's count (UI-PRMD m08 shoulder extension, the simulated shoulder flexion and
extension) the count with the shipped counting angle, with it wrapped at each seam candidate, and with a folded
flexion (folded_flexion below: the abduction's fix turned to the sagittal plane) is printed too.

    python bench/flexion_seam.py [--data ../shared/data] [--sources uiprmd,vicon,keraal,hdm05,cmu,utkinect,sim]
                                 [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:
    sys.path.insert(0, str(ROOT_DIR))

from kinect_agent import formats  # noqa: E402
from kinect_agent.analysis import series  # noqa: E402
from kinect_agent.analysis.angles import FORWARD_WEIGHT, counting_angles  # noqa: E402
from kinect_agent.analysis.exercise import EXERCISES  # noqa: E402
from kinect_agent.analysis.range_of_motion import range_of_motion  # noqa: E402
from kinect_agent.analysis.repetitions import count_repetitions  # noqa: E402
from kinect_agent.body.angles import body_frame, joint_angles  # noqa: E402
from kinect_agent.formats import ui_prmd, ui_prmd_vicon  # noqa: E402
from kinect_agent.recording import Metadata, Recording  # noqa: E402
from kinect_agent.skeleton import INDEX  # noqa: E402
from kinect_agent.sources.simulator import simulate  # noqa: E402

RATE_HZ = 30.0  # mocap is thinned to about this rate
JUMP_DEG = 60.0  # a step larger than this in one frame (at 30 Hz: 1800°/s) is no limb's movement
LIMBS = {"shoulder_flexion": ("SHO", "ELB"), "hip_flexion": ("HIP", "KNE")}
NAMES = tuple(f"{prefix}_{side}" for prefix in LIMBS for side in "LR")
SECTOR = {"shoulder_flexion": (-90.0, 200.0), "hip_flexion": (-60.0, 170.0)}  # what sagittal movements reach
KINDS = {"correct": "Segmented Movements", "incorrect": "Incorrect Segmented Movements"}
SUBJECTS = ("s01", "s02", "s03", "s04", "s05")
UIPRMD = {spec.uiprmd_movement: slug for slug, spec in EXERCISES.items() if spec.uiprmd_movement}
SIM_VIEWS = (0, 30, 60)
SIM_SEEDS = (0, 1, 2)
SIM_REPS = 5
BACK_EDGES = np.arange(-135.0, -59.0, 15.0)  # the sectors behind the trunk where a sagittal seam can go
SEAMS = (-120.0, -110.0, -100.0, -95.0, -90.0, -85.0, -80.0)  # candidates, degrees (shipped: SAGITTAL_SEAM_DEG)


def thin(rec: Recording) -> Recording:
    """Returns rec thinned to about RATE_HZ (every k-th frame)."""
    step = max(1, int(round(rec.rate_hz / RATE_HZ))) if np.isfinite(rec.rate_hz) else 1
    keep = np.arange(0, rec.n_frames, step)
    return Recording(rec.t[keep], rec.positions[keep], rec.state[keep], rec.meta)


def joined(recs: list[Recording]) -> Recording:
    """Returns the recordings one after the other at the first one's rate (episodes of one movement and subject)."""
    positions = np.concatenate([r.positions for r in recs])
    t = np.arange(len(positions)) / recs[0].rate_hz
    return Recording.from_positions(t, positions, Metadata(device="mocap", rate_hz=recs[0].rate_hz))


def recordings(data: Path, sources: set[str]) -> Iterator[tuple[str, str, str | None, Recording]]:
    """Yields (source, label, exercise slug or None, recording) for every recording of the sources asked."""
    if "uiprmd" in sources:
        for kind, folder in KINDS.items():
            for movement, slug in sorted(UIPRMD.items()):
                for subject in SUBJECTS:
                    rec = ui_prmd.read_episodes(
                        data / "ui-prmd" / folder / "Kinect", movement=movement, subject=subject
                    )
                    yield "ui-prmd kinect", f"{movement} {subject} {kind}", slug, rec
    if "vicon" in sources:
        for kind, folder in KINDS.items():
            for movement, slug in sorted(UIPRMD.items()):
                paths = sorted((data / "ui-prmd" / folder / "Vicon" / "Positions").glob(f"{movement}_s01_e*"))
                if paths:
                    rec = thin(joined([ui_prmd_vicon.read(p) for p in paths]))
                    yield "ui-prmd vicon", f"{movement} s01 {kind}", slug, rec
    if "keraal" in sources:
        for p in sorted((data / "keraal").rglob("*.txt")):
            if "Kinect" in p.name or "Vicon" in p.name or p.name.startswith("SkeletonSequence"):
                yield "keraal", f"{p.parent.name}/{p.stem}", None, thin(formats.read(p))
    if "hdm05" in sources:
        for motion in sorted((data / "hdm05").glob("*1Reps*")):
            clips = sorted(p for p in motion.glob("*.amc") if p.name.split("_")[1] in ("bd", "bk"))
            for actor in ("bd", "bk"):
                mine = [thin(formats.read(p)) for p in clips if p.name.split("_")[1] == actor]
                if mine:
                    yield "hdm05", f"{motion.name} {actor} ({len(mine)} clips)", None, joined(mine)
    if "cmu" in sources:
        yield "cmu", "13_29", None, thin(formats.read(data / "cmu-mocap" / "13_29.bvh"))
    if "utkinect" in sources:
        for p in sorted((data / "utkinect").glob("joints_s0[1-5]_e0*.txt")):
            yield "utkinect", p.stem, None, formats.read(p)
    if "sim" in sources:
        for slug in EXERCISES:
            spec = EXERCISES[slug]
            for view in SIM_VIEWS:
                for seed in SIM_SEEDS:
                    try:
                        measured, _, _ = simulate(slug, SIM_REPS, view_deg=view, seed=seed)
                    except ValueError:  # a view the simulator's error tables do not cover for this pose
                        continue
                    measured.meta.extra["true_count"] = SIM_REPS
                    yield "simulator", f"{slug} {view}° seed {seed}", spec.slug, measured


def off_plane(positions: np.ndarray, prefix: str, side: str) -> np.ndarray:
    """Returns (T,) degrees: the limb of `prefix` on `side` out of the sagittal plane (0 in it, 90 along its normal).

    positions: (T, J, 3) float, metres, camera frame, NaN = untracked (gives NaN)."""
    _, left, _ = body_frame(positions)
    proximal, distal = LIMBS[prefix]
    limb = positions[:, INDEX[f"{distal}_{side}"]] - positions[:, INDEX[f"{proximal}_{side}"]]
    with np.errstate(invalid="ignore", divide="ignore"):
        sin = np.abs(series.dot3(limb, left)) / series.norm3(limb)
    return np.degrees(np.arcsin(np.clip(sin, 0.0, 1.0)))


def folded_flexion(positions: np.ndarray, side: str, weight: float = FORWARD_WEIGHT) -> np.ndarray:
    """Returns (T,) degrees in [0, 180]: atan2(hypot(fwd, weight * out), down) of the upper arm (its parts along the
    trunk's forward, outward and down directions): |shoulder flexion| while the arm moves in the sagittal plane,
    continuous wherever the arm points. positions: (T, J, 3) float, metres, camera frame, NaN = untracked."""
    up, left, forward = body_frame(positions)
    outward = left if side == "L" else -left
    arm = positions[:, INDEX[f"ELB_{side}"]] - positions[:, INDEX[f"SHO_{side}"]]
    along = np.hypot(series.dot3(arm, forward), weight * series.dot3(arm, outward))
    return np.degrees(np.arctan2(along, -series.dot3(arm, up)))


def signed(folded: np.ndarray, measured: np.ndarray) -> np.ndarray:
    """Returns folded (T,) degrees with the sign of the measured angle's median over the frames raised > 20°."""
    raised = np.isfinite(measured) & (folded > 20.0)
    return -folded if raised.any() and np.median(measured[raised]) < 0 else folded


def steps(x: np.ndarray, jump_deg: float = JUMP_DEG) -> int:
    """Returns how many times x (T,) degrees steps by more than jump_deg between consecutive defined frames."""
    defined = x[np.isfinite(x)]
    return int(np.sum(np.abs(np.diff(defined)) > jump_deg)) if defined.size > 1 else 0


def rewrap(x: np.ndarray, seam: float) -> np.ndarray:
    """Returns x (..., degrees, a planar angle) wrapped into [seam, seam + 360)."""
    return seam + np.mod(x - seam, 360.0)


def angle_numbers(
    t: np.ndarray, smoothed: np.ndarray, name: str, angles: dict[str, dict[str, np.ndarray]]
) -> dict[str, Any]:
    """Returns the numbers of one angle `name` (module docstring) of positions `smoothed` (T, J, 3) m at t (T,) s;
    angles: {"measured", "unmasked", "counted": {name: (T,) degrees}}."""
    lo, hi = SECTOR[name[:-2]]
    off = off_plane(smoothed, name[:-2], name[-1])
    tracked = np.isfinite(off)
    n = max(1, int(tracked.sum()))
    measured, unmasked = angles["measured"][name], angles["unmasked"][name]
    sector = tracked & ((unmasked > hi) | (unmasked < lo))
    rom = range_of_motion(t, {name: measured}, presmoothed=True)[name]
    return {
        "off60": 100.0 * float(np.sum(off[tracked] >= 60.0)) / n,
        "off80": 100.0 * float(np.sum(off[tracked] >= 80.0)) / n,
        "sector": 100.0 * float(sector.sum()) / n,
        "sector_defined": 100.0 * float(np.sum(sector & np.isfinite(measured))) / n,
        "count_steps": steps(angles["counted"][name]),
        "measured_steps": steps(measured),
        "rom": [rom["min_deg"], rom["max_deg"]],
        "back": np.histogram(rewrap(unmasked[tracked & (off < 60.0)], -180.0), BACK_EDGES)[0].tolist(),
        "seams": {str(seam): at_seam(t, measured, seam, tracked, n) for seam in SEAMS},
    }


def at_seam(t: np.ndarray, measured: np.ndarray, seam: float, tracked: np.ndarray, n: int) -> dict[str, Any]:
    """Returns the measured angle (T,) degrees wrapped at `seam`: its steps across the seam, its range of motion and
    the % of the n tracked frames (tracked: (T,) bool) within 15° of the seam."""
    x = rewrap(measured, seam)
    rom = range_of_motion(t, {"x": x}, presmoothed=True)["x"]
    near = tracked & np.isfinite(x) & ((x < seam + 15.0) | (x > seam + 345.0))
    return {"wraps": steps(x, 180.0), "rom": [rom["min_deg"], rom["max_deg"]], "near": 100.0 * float(near.sum()) / n}


def counts(rec: Recording, smoothed: np.ndarray, slug: str, measured: dict[str, np.ndarray]) -> dict[str, Any]:
    """Returns the counts of a recording of exercise `slug` on the shipped counting angles, on them wrapped at each
    seam of SEAMS and on the folded flexion, and the counting signals' steps."""
    names = EXERCISES[slug].defining_angles
    shipped = counting_angles(smoothed, names, measured)
    folded = {n: signed(folded_flexion(smoothed, n[-1]), measured[n]) for n in names}

    def count(angles: dict[str, np.ndarray]) -> int:
        return len(count_repetitions(rec.t, angles, names).repetitions)

    return {
        "shipped": count(shipped),
        "folded": count(folded),
        "shipped_steps": max(steps(shipped[n]) for n in names),
        "folded_steps": max(steps(folded[n]) for n in names),
        "seams": {str(seam): count({n: rewrap(shipped[n], seam) for n in names}) for seam in SEAMS},
        "true": rec.meta.extra.get("true_count", 10),
    }


def measure(rec: Recording, slug: str | None) -> dict[str, Any]:
    """Returns the numbers of the module docstring for one recording (both sides of each angle)."""
    smoothed = series.smooth_positions(rec.t, rec.positions)
    measured = joint_angles(smoothed)
    angles = {
        "measured": measured,
        "unmasked": joint_angles(smoothed, mask_off_plane=False),
        "counted": counting_angles(smoothed, NAMES, measured),
    }
    out: dict[str, Any] = {"frames": rec.n_frames}
    out |= {name: angle_numbers(rec.t, smoothed, name, angles) for name in NAMES}
    if slug is not None and any(n.startswith("shoulder_flexion") for n in EXERCISES[slug].defining_angles):
        out["counts"] = counts(rec, smoothed, slug, measured)
    return out


def print_regions(mine: list[dict[str, Any]], name: str) -> None:
    """Prints one angle's share of frames off its plane and in the sector no sagittal movement reaches, its steps
    and the recordings whose range leaves that sector, over the recordings `mine`."""
    lo, hi = SECTOR[name[:-2]]
    frames = max(1, sum(r["frames"] for r in mine))
    pct = {key: sum(r[name][key] * r["frames"] for r in mine) / frames for key in ("off60", "off80", "sector",
                                                                                  "sector_defined")}  # fmt: skip
    beyond = [r for r in mine if (r[name]["rom"][1] or 0) > hi or (r[name]["rom"][0] or 0) < lo]
    print(f"  {name:<19} off≥60 {pct['off60']:5.1f} %  off≥80 {pct['off80']:5.2f} % "
          f"(in {sum(r[name]['off80'] > 0 for r in mine)} recs)  "
          f"sector {pct['sector']:5.2f} % (defined {pct['sector_defined']:5.2f} %)  "
          f"steps counted {sum(r[name]['count_steps'] for r in mine)} "
          f"measured {sum(r[name]['measured_steps'] for r in mine)}  "
          f"rom beyond [{lo:g}, {hi:g}] in {len(beyond)}")  # fmt: skip
    for r in beyond:
        print(f"      {r['label']}: rom {r[name]['rom']}, sector {r[name]['sector']:.1f} % "
              f"(defined {r[name]['sector_defined']:.1f} %), off≥60 {r[name]['off60']:.1f} %")  # fmt: skip


def print_seams(mine: list[dict[str, Any]], name: str) -> None:
    """Prints one angle's defined frames per sector behind the trunk and, per seam candidate, the recordings of
    `mine` whose measured curve crosses it and whose range spans it."""
    frames = max(1, sum(r["frames"] for r in mine))
    back = np.sum([r[name]["back"] for r in mine], axis=0)
    sectors = zip(BACK_EDGES[:-1], BACK_EDGES[1:], back, strict=True)
    print(f"  {name:<19} defined frames per sector " + "  ".join(f"{a:.0f}..{b:.0f}: {k}" for a, b, k in sectors))
    for seam in SEAMS:
        cases = [(r["label"], r["frames"], r[name]["seams"][str(seam)]) for r in mine]
        wrapped = [label for label, _, c in cases if c["wraps"]]
        wide = sum((c["rom"][1] or 0) - (c["rom"][0] or 0) > 300 for _, _, c in cases)
        near = sum(c["near"] * f for _, f, c in cases) / frames
        print(f"  seam {seam:6.0f}  {name:<19} recordings whose measured curve crosses it {len(wrapped):>3}, "
              f"range > 300° {wide:>3}, frames within 15° {near:5.2f} %  {', '.join(wrapped[:6])}")  # fmt: skip


def print_counts(mine: list[dict[str, Any]]) -> None:
    """Prints the counts of the recordings of `mine` whose exercise counts on shoulder flexion."""
    for r in (r for r in mine if "counts" in r):
        c = r["counts"]
        flag = "" if c["shipped"] == c["folded"] else "   <- differs"
        by_seam = " ".join(f"{k}:{v}" for k, v in c["seams"].items())
        print(f"  count {r['label']:<44} true {c['true']:>2} shipped {c['shipped']:>2} "
              f"(steps {c['shipped_steps']})  folded {c['folded']:>2} (steps {c['folded_steps']}){flag}  "
              f"by seam {by_seam}")  # fmt: skip


def print_rows(rows: list[dict[str, Any]]) -> None:
    """Prints per source the numbers of every angle, the seam candidates and the counts."""
    for source in dict.fromkeys(r["source"] for r in rows):
        mine = [r for r in rows if r["source"] == source]
        print(f"\n{source}: {len(mine)} recordings, {sum(r['frames'] for r in mine)} frames")
        for name in NAMES:
            print_regions(mine, name)
        for name in NAMES:
            print_seams(mine, name)
        print_counts(mine)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=ROOT_DIR.parent / "shared" / "data")
    parser.add_argument("--sources", default="uiprmd,vicon,keraal,hdm05,cmu,utkinect,sim")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    started = time.perf_counter()
    rows = []
    for source, label, slug, rec in recordings(args.data, set(args.sources.split(","))):
        rows.append({"source": source, "label": label, "slug": slug, **measure(rec, slug)})
    print_rows(rows)
    print(f"\n{len(rows)} recordings in {time.perf_counter() - started:.0f} s")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
