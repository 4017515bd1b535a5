"""Offline pipeline variants against CV Kalman + RTS and One Euro, per motion, view and seed (issue 13 study).

Prints per row: RMSE (bias/random) mm and elbow/knee RMSE ° of raw, CV Kalman + RTS, One Euro and each variant;
the baselines are run once per clip. A variant is NAME:SETTING=VALUE,SETTING=VALUE (PipelineConfig fields) or
"default".

    python bench/k1_variants.py --motions hdm05_squat1Reps ui_prmd_m05 --views 0 60 --seeds 1 2 3 --device kinect1 \
        --variants default "body:residual_offset=body"
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:
    sys.path.insert(0, str(ROOT_DIR))

from bench.accuracy import MotionSums, motion_cases, motions, pipeline_config, run_method  # noqa: E402
from kinect_agent.processing.config import PipelineConfig  # noqa: E402


def parse_variant(text: str) -> tuple[str, PipelineConfig]:
    """Returns (name, PipelineConfig) of a variant "NAME:SETTING=VALUE,SETTING=VALUE"."""
    name, _, sets = text.partition(":")
    return name, pipeline_config([s for s in sets.split(",") if s])


def _rmse_mm(metrics: dict[str, float | None]) -> float:
    """Returns the RMSE (mm) of a method's MotionSums.metrics()."""
    rmse = metrics["rmse_mm"]
    if rmse is None:
        raise ValueError("no joint-frames were measured")
    return rmse


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--motions", nargs="+", default=["hdm05_squat1Reps"])
    parser.add_argument("--views", type=int, nargs="+", default=[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1])
    parser.add_argument("--device", default="kinect1")
    parser.add_argument("--variants", nargs="+", default=["default"])
    args = parser.parse_args()
    variants = [parse_variant(v) for v in args.variants]
    base = variants[0][1]
    chosen = [m for m in motions() if m.name in args.motions]
    names = ["raw", "cv_kalman_rts", "one_euro", *(f"off:{n}" for n, _ in variants)]
    print("| motion | view | seed | " + " | ".join(names) + " | margin vs CV / 1€ per variant |")
    print("|---|---|---|" + "---|" * (len(names) + 1))
    for motion in chosen:
        for view in args.views:
            for seed in args.seeds:
                sums = {n: MotionSums() for n in names}
                for case in motion_cases(motion, view, seed, args.device):
                    for n in names[:3]:
                        sums[n].add_case(case, run_method(n, case.measured, base)[0])
                    for n, cfg in variants:
                        sums[f"off:{n}"].add_case(case, run_method("pipeline_offline", case.measured, cfg)[0])
                m = {n: s.metrics() for n, s in sums.items()}
                cells = [f"{m[n]['rmse_mm']:.1f} ({m[n]['bias_mm']:.1f}/{m[n]['random_mm']:.1f}) "
                         f"{m[n]['angle_rmse_deg']:.2f}°" for n in names]  # fmt: skip
                cv, euro = _rmse_mm(m["cv_kalman_rts"]), _rmse_mm(m["one_euro"])
                margins = [f"{_rmse_mm(m[f'off:{n}']) - cv:+.1f}/{_rmse_mm(m[f'off:{n}']) - euro:+.1f}"
                           for n, _ in variants]  # fmt: skip
                print(f"| {motion.name} | {view}° | {seed} | " + " | ".join(cells) + " | " + "; ".join(margins) + " |",
                      flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
