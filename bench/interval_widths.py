"""Widths of the 95 % range-of-motion intervals on real recordings (prints numbers; not a test).

    .venv/bin/python bench/interval_widths.py [--subjects s01 s03]

Real Kinect v2 (UI-PRMD correct executions, m01-m10 of each subject, episodes joined) through the home agent's
pipeline, then the server's intervals (kinect_agent.analysis.intervals.rom_intervals) from its angle SDs. There is no
truth here, so only the widths: the median and the 90th percentile of the half-widths of every angle's min_deg,
max_deg (peak) and range_deg, in degrees. Coverage is measured on simulated sessions (bench/uncertainty.py); this
shows what a therapist sees on real sessions, whose repetitions vary more than the simulator's.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from kinect_agent.analysis import series  # noqa: E402
from kinect_agent.analysis.intervals import rom_intervals  # noqa: E402
from kinect_agent.body.angles import joint_angles  # noqa: E402
from kinect_agent.formats import ui_prmd  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "ui-prmd" / "Segmented Movements" / "Kinect"
KINDS = ("min_deg", "max_deg", "range_deg")


def half_widths(movement: str, subject: str) -> dict[str, list[float]]:
    """Returns {kind: [half-width, degrees, of each angle's interval]} of one recording."""
    result = process(ui_prmd.read_episodes(DATA, movement=movement, subject=subject))
    t = result.filtered.t
    smoothed = series.smooth_positions(t, result.filtered.positions)
    out: dict[str, list[float]] = {k: [] for k in KINDS}
    if result.angle_sd is None:
        raise RuntimeError("the offline pipeline returned no angle SDs")
    for intervals in rom_intervals(t, joint_angles(smoothed), result.angle_sd, smoothed).intervals.values():
        for kind, (lo, hi) in (intervals or {}).items():
            out[kind].append(0.5 * (hi - lo))
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", nargs="+", default=["s01", "s03"])
    args = parser.parse_args()
    if not DATA.is_dir():
        raise SystemExit(f"{DATA} is missing (../shared beside the repository)")
    pooled: dict[str, list[float]] = {k: [] for k in KINDS}
    for movement in (f"m{i:02d}" for i in range(1, 11)):
        for subject in args.subjects:
            widths = half_widths(movement, subject)
            print(f"{movement} {subject}  median half-width  " + "  ".join(
                f"{k} {np.median(v):5.1f}°" for k, v in widths.items() if v))  # fmt: skip
            for k, v in widths.items():
                pooled[k] += v
    for label, q in (("median", 50), ("90th percentile", 90)):
        print(f"{label:>16}: " + "  ".join(f"{k} {np.percentile(v, q):5.1f}°" for k, v in pooled.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
