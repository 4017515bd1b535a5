"""Where the filtered range of motion leaves the raw data's envelope (issue 24.1), and why.

For every case of the property test (tests/backend/session_texts/test_numbers_agree.py: the real recordings' sample, the
simulator's exercises at views 0° and 60°, the demo's sessions) this runs the agent's path (make_payload: filter,
angle SDs; then the session file as the server stores it) and measures, per angle of
kinect_agent.body.angles.ANGLE_NAMES, as the session page does:
    raw envelope   the raw angle's (joint_angles of the raw positions) 0.5th-99.5th percentiles
                   ± intervals.RAW_MARGIN_DEG (intervals.beyond_raw)
    filtered       the key numbers: range_of_motion of the measured angles (smoothed filtered positions)
An angle whose filtered min or max leaves the envelope is listed with a diagnosis, frame by frame over the frames
where the measured filtered angle lies outside the envelope ("outside frames"):
    raw-nan    the raw angle is undefined there (off its plane, or the rotation's hanging arm) in most of them:
               the filtered angle is defined where the camera's is not;
    seam       the filtered and raw angles differ by more than 180° there (one of them crossed the planar seam);
    joints     the angle of the filtered positions (unsmoothed) differs from the raw one by more than
               RAW_MARGIN_DEG in most outside frames, with both defined: the filter moved the joints;
    smoothing  the unsmoothed filtered angle stays in the envelope but the smoothed one leaves it;
    definition otherwise (the raw angle itself reaches there in those frames, the percentiles differ).
Last column: whether the session (report.analyze_recording) still shows that range ("SHOWN") or withholds it with its
reason (range_of_motion_withheld, since 2026-11-28).
Per listed angle it also prints the median limb angle off the angle's plane over the outside frames (for the planar
angles: 90° = the limb along the plane's normal, where the angle is ill-defined) and the median displacement of the
angle's distal joint, filtered − raw (mm).

    .venv/bin/python bench/raw_envelope.py [--only SUBSTRING] [--sources real,sim,demo] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import asdict, dataclass
from functools import partial
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from kinect_agent.analysis.angles import measured_angles  # noqa: E402
from kinect_agent.analysis.exercise import EXERCISES  # noqa: E402
from kinect_agent.analysis.intervals import RAW_ENVELOPE_PCT, RAW_MARGIN_DEG  # noqa: E402
from kinect_agent.analysis.range_of_motion import range_of_motion  # noqa: E402
from kinect_agent.analysis.report import analyze_recording  # noqa: E402
from kinect_agent.body.angles import ANGLE_NAMES, body_frame, joint_angles  # noqa: E402
from kinect_agent.capture import capture, make_payload  # noqa: E402
from kinect_agent.formats import session_file  # noqa: E402
from kinect_agent.formats.session_file import SessionPayload  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402
from kinect_agent.skeleton import INDEX  # noqa: E402
from kinect_agent.sources.simulator import EXERCISES as SIMULATED  # noqa: E402
from kinect_agent.sources.simulator import simulate  # noqa: E402
from tests.backend.session_texts.test_numbers_agree import DEMO, read_real, real_cases, thin  # noqa: E402

# angle prefix -> (proximal, distal) joint of the limb it measures, and the plane it lies in (its normal's name)
LIMBS = {
    "elbow_flexion": ("ELB", "WRI"),
    "knee_flexion": ("KNE", "ANK"),
    "shoulder_flexion": ("SHO", "ELB"),
    "shoulder_abduction": ("SHO", "ELB"),
    "shoulder_rotation": ("ELB", "WRI"),
    "hip_flexion": ("HIP", "KNE"),
    "hip_abduction": ("HIP", "KNE"),
}
NORMAL = {"shoulder_flexion": "left", "hip_flexion": "left", "shoulder_abduction": "forward"}


@dataclass
class Finding:
    """One angle of one case whose filtered range leaves the raw envelope (degrees, mm)."""

    case: str
    angle: str
    envelope: tuple[float, float]
    raw_pct: tuple[float, float]
    filtered: tuple[float, float]
    by: float
    cause: str
    outside_frames: int
    raw_nan_frac: float
    seam_frac: float
    joints_frac: float
    off_plane_deg: float | None
    distal_shift_mm: float | None


Case = tuple[str, str, Callable[[], Recording]]  # label, exercise slug, the raw recording


def cases(sources: set[str]) -> list[Case]:
    """Returns (label, exercise, a function returning the raw recording) of every case of the sources."""
    out: list[Case] = []
    if "real" in sources:
        out += [(label, slug, partial(_real, key)) for label, key, slug in real_cases()]
    if "sim" in sources:
        for view in (0, 60):
            out += [(f"sim {e} {view}°", e, partial(_simulated, e, view)) for e in SIMULATED]
    if "demo" in sources:
        out += [
            (f"demo {e}", e, partial(capture, "simulator", exercise=e, reps=10, seed=1 + k)) for k, e in enumerate(DEMO)
        ]
    return out


def _real(key: str) -> Recording:
    return thin(read_real(key))


def _simulated(exercise: str, view: int) -> Recording:
    return simulate(exercise, 5, view_deg=view, seed=11 + view)[0]


def withheld_ranges(payload: SessionPayload, slug: str) -> set[str]:
    """Returns the angles whose range of motion the session's analysis withholds (range_of_motion_withheld)."""
    doc = analyze_recording(payload.raw, EXERCISES[slug], filtered=payload.filtered, angle_sd=payload.angle_sd)
    return set(doc.range_of_motion_withheld or {})


def _off_plane_deg(positions: np.ndarray, angle: str) -> np.ndarray:
    """Returns (T,) degrees: the limb's angle out of the planar angle's plane (NaN for other angles)."""
    prefix, side = angle[:-2], angle[-1]
    if prefix not in NORMAL:
        return np.full(positions.shape[0], np.nan)
    up, left, forward = body_frame(positions)
    normal = left if NORMAL[prefix] == "left" else forward
    a, b = (INDEX[f"{j}_{side}"] for j in LIMBS[prefix])
    limb = positions[:, b] - positions[:, a]
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.abs(np.sum(limb * normal, axis=-1)) / np.linalg.norm(limb, axis=-1)
    return np.degrees(np.arcsin(np.clip(cos, 0.0, 1.0)))


def study(label: str, payload: SessionPayload) -> tuple[list[Finding], int]:
    """Returns the findings of one case (its session as the agent sends it) and the number of angles checked."""
    raw, filtered = payload.raw, payload.filtered
    assert filtered is not None
    t = raw.t
    measured = measured_angles(t, filtered.positions).angles
    rom = range_of_motion(t, measured, presmoothed=True)
    raw_angles = joint_angles(raw.positions)
    unsmoothed = joint_angles(filtered.positions)
    findings: list[Finding] = []
    checked = 0
    for name in ANGLE_NAMES:
        r, x = rom[name], raw_angles[name]
        finite = x[np.isfinite(x)]
        if r["min_deg"] is None or finite.size == 0:
            continue
        checked += 1
        pct = np.percentile(finite, RAW_ENVELOPE_PCT)
        lo, hi = pct + np.array([-RAW_MARGIN_DEG, RAW_MARGIN_DEG])
        fmin, fmax = float(r["min_deg"]), float(r["max_deg"])  # type: ignore[arg-type]
        by = max(0.0, lo - fmin, fmax - hi)
        if by <= 0.0:
            continue
        m = measured[name]
        with np.errstate(invalid="ignore"):
            outside = np.isfinite(m) & ((m < lo) | (m > hi))
        k = np.flatnonzero(outside)
        xr, xf = x[k], unsmoothed[name][k]
        both = np.isfinite(xr) & np.isfinite(xf)
        raw_nan = float(np.mean(~np.isfinite(xr))) if k.size else 0.0
        seam = float(np.mean(np.abs(xf - xr)[both] > 180.0)) if both.any() else 0.0
        joints = float(np.mean(np.abs(xf - xr)[both] > RAW_MARGIN_DEG)) if both.any() else 0.0
        with np.errstate(invalid="ignore"):
            unsmoothed_out = float(np.mean((xf < lo) | (xf > hi))) if k.size else 0.0
        if raw_nan > 0.5:
            cause = "raw-nan"
        elif seam > 0.5:
            cause = "seam"
        elif joints > 0.5:
            cause = "joints"
        elif unsmoothed_out < 0.5:
            cause = "smoothing"
        else:
            cause = "definition"
        off = _off_plane_deg(filtered.positions, name)[k]
        prefix, side = name[:-2], name[-1:]
        shift = None
        if prefix in LIMBS and k.size:
            d = INDEX[f"{LIMBS[prefix][1]}_{side}"]
            delta = np.linalg.norm(filtered.positions[k, d] - raw.positions[k, d], axis=-1)
            shift = float(np.nanmedian(delta) * 1000.0) if np.isfinite(delta).any() else None
        findings.append(Finding(
            label, name, (round(float(lo), 1), round(float(hi), 1)), (round(float(pct[0]), 1), round(float(pct[1]), 1)),
            (fmin, fmax), round(by, 1), cause, int(k.size), round(raw_nan, 2), round(seam, 2), round(joints, 2),
            None if not np.isfinite(off).any() else round(float(np.nanmedian(off)), 1),
            None if shift is None else round(shift, 1),
        ))  # fmt: skip
    return findings, checked


def main(argv: list[str] | None = None) -> int:
    """Runs the study and prints one line per finding, then the counts per angle and per cause."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--only", help="only the cases whose label contains this")
    parser.add_argument("--sources", default="real,sim,demo", help="comma-separated: real, sim, demo")
    parser.add_argument("--json", type=Path, help="write the findings here")
    args = parser.parse_args(argv)
    todo = [c for c in cases(set(args.sources.split(","))) if not args.only or args.only in c[0]]
    start = time.perf_counter()
    every: list[Finding] = []
    leaving: set[str] = set()
    shown_leaving = 0
    for label, slug, f in todo:
        sent = make_payload(f(), session_id="00000000-0000-4000-8000-000000000001", created_at="2026-11-27T00:00:00Z")
        payload = session_file.decode(session_file.encode(sent), max_frames=10**7, max_decoded_bytes=2**31)  # stored
        found, _ = study(label, payload)
        withheld = withheld_ranges(payload, slug)
        every += found
        leaving |= {x.case for x in found}
        for x in found:
            shown = x.angle not in withheld
            shown_leaving += shown
            print(
                f"{x.case:52s} {x.angle:22s} raw {x.raw_pct} env {x.envelope} filtered {x.filtered} by {x.by:5.1f}"
                f" {x.cause:10s} n={x.outside_frames} rawnan={x.raw_nan_frac} seam={x.seam_frac}"
                f" joints={x.joints_frac} off-plane={x.off_plane_deg} shift={x.distal_shift_mm} mm"
                f" {'SHOWN' if shown else 'withheld'}",
                flush=True,
            )
    print(
        f"\n{len(leaving)} of {len(todo)} cases leave the envelope ({len(every)} angles; the session shows "
        f"{shown_leaving} of those ranges), {time.perf_counter() - start:.0f} s"
    )
    for key, counts in (("angle", Counter(x.angle for x in every)), ("cause", Counter(x.cause for x in every))):
        print(f"per {key}: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
    if args.json:
        args.json.write_text(json.dumps([asdict(x) for x in every], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
