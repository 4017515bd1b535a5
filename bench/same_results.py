"""Checks that a change to the pipeline's speed leaves its results as they were (issue 24, point 5).

Runs pipeline.process (offline defaults, the device's settings) on real recordings in ../shared/data (UI-PRMD
s01-s05 Kinect, KERAAL Kinect of the Vicon pairs, UTKinect s01-s05) and on the outlier-heavy simulated session,
and either saves every result (filtered positions (T, J, 3) m, outlier probabilities (T, J), segment lengths (19,)
m, rotations q_root (T, 4) and q_local (T, 19, 4) wxyz, angle SDs {angle: (T,)} degrees) to --save DIR, or compares
them with a saved run: --compare DIR prints the largest absolute difference per quantity and recording, and exits 1
when any exceeds --tol (default 1e-9). A quantity the saved run lacks (saved by an older version) is not compared.
Either way it checks that pipeline.filter_recording (what `kinect-agent filter` runs without --params) gives
process()'s filtered recording byte for byte.
Run the old code with --save (e.g. from `git archive` of the old commit), the new with --compare.
    python bench/same_results.py --save DIR | --compare DIR [--tol 1e-9] [--quick]
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:  # `python bench/same_results.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT_DIR))

from bench.sessions import outlier_heavy_session  # noqa: E402
from kinect_agent import formats  # noqa: E402
from kinect_agent.processing.config import config_for_device  # noqa: E402
from kinect_agent.processing.pipeline import filter_recording, process  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402

DATA = Path(os.environ.get("COACH_SHARED_DIR", "/work/shared")) / "data"  # as tests/conftest.py, default this machine


def recordings(quick: bool) -> dict[str, Recording]:
    """Returns {name: recording}: real Kinect recordings of every shared source, and the outlier-heavy session."""
    prmd = DATA / "ui-prmd" / "Segmented Movements" / "Kinect" / "Positions"
    paths = [(p, "ui_prmd") for s in range(1, 6) for p in sorted(prmd.glob(f"m0[1-9]_s0{s}_e01_positions.txt.gz"))]
    paths += [(p, "keraal") for p in sorted((DATA / "keraal" / "kinect_vicon_pairs").glob("*Kinect*.txt"))]
    paths += [(DATA / "utkinect" / f"joints_s0{s}_e01.txt", "utkinect") for s in range(1, 6)]
    if quick:
        paths = paths[::9]
    out = {f"{fmt}/{p.name}": formats.read(p, fmt) for p, fmt in paths}
    out["sim/outlier_heavy_2min"] = outlier_heavy_session(2.0 if quick else 10.0)
    return out


def results(rec: Recording) -> dict[str, np.ndarray]:
    """Returns the pipeline's numeric results of one recording, flat {quantity: array}. Raises RuntimeError when
    filter_recording (`kinect-agent filter` without --params) gives another recording than process(), byte for byte."""
    config = config_for_device(rec.meta.device)
    r = process(rec, config=config)
    if r.params.outlier_prob is None:
        raise RuntimeError("the offline pipeline returned no outlier probabilities")
    only = filter_recording(rec, config=config).filtered
    if not all(getattr(only, a).tobytes() == getattr(r.filtered, a).tobytes() for a in ("t", "positions", "state")):
        raise RuntimeError("filter_recording's recording differs from process()'s")
    out = {
        "positions": r.filtered.positions,
        "outlier_prob": r.params.outlier_prob,
        "segment_lengths": r.params.segment_lengths,
        "q_root": r.params.q_root,
        "q_local": r.params.q_local,
    }
    out.update({f"joint_angles/{k}": v for k, v in r.params.joint_angles.items()})
    out.update({f"angle_sd/{k}": v for k, v in (r.angle_sd or {}).items()})
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--save", type=Path)
    group.add_argument("--compare", type=Path)
    parser.add_argument("--tol", type=float, default=1e-9)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args(argv)
    worst, failed = 0.0, 0
    for name, rec in recordings(args.quick).items():
        got = results(rec)
        file = (args.save or args.compare) / (name.replace("/", "__") + ".npz")
        if args.save:
            file.parent.mkdir(parents=True, exist_ok=True)
            np.savez_compressed(file, allow_pickle=True, **got)  # the default, named: numpy's stub matches **got to it
            print(f"saved {name}: {rec.n_frames} frames", flush=True)
            continue
        saved = np.load(file)
        diffs = {k: float(np.nanmax(np.abs(got[k] - saved[k]), initial=0.0)) for k in saved.files}
        nan_moved = [k for k in saved.files if not np.array_equal(np.isnan(got[k]), np.isnan(saved[k]))]
        top = max(diffs.values())
        worst = max(worst, top)
        bad = top > args.tol or nan_moved
        failed += bool(bad)
        key = max(diffs, key=lambda k: diffs[k])
        print(f"{'DIFF' if bad else 'same'} {name}: largest difference {top:.3g} ({key})"
              + (f"; NaN pattern differs in {nan_moved}" if nan_moved else ""), flush=True)  # fmt: skip
    if args.compare:
        print(f"{failed} recording(s) differ by more than {args.tol:g}; largest difference overall {worst:.3g}")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
