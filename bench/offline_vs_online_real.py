"""The offline smoother against its own online filter per joint on real Kinect v2 / Vicon pairs (issue 24, point 2).

UI-PRMD, correctly performed episodes of movements m01-m10 (../shared/data holds Vicon for s01 only, e01-e10; Kinect
and Vicon were segmented separately): aligned and accepted by bench/offset_model.make_pair with its checks (lag by
speed correlation agreeing with the lag by registration RMS, correlation >= 0.8, RMS <= 0.1 m). Each method's
estimate (T, J, 3) m is compared with the Vicon joints registered onto that estimate by a trimmed rigid fit
(bench/offset_model.register), so the mean offset of the registered joints is counted against neither filter.
Prints per movement the position RMSE per joint (pooled over episodes) offline (pipeline.process) and online
(process(online=True)), and the joints where offline > online.
    python bench/offline_vs_online_real.py [--subjects 1] [--episodes 1 2 ... 10] [--set NAME=VALUE ...]
"""

from __future__ import annotations

import argparse
import ast
import sys
from pathlib import Path

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:  # `python bench/offline_vs_online_real.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT_DIR))

from bench import offset_model as om  # noqa: E402
from kinect_agent import skeleton  # noqa: E402
from kinect_agent.evaluation.pairs import joint_mask  # noqa: E402
from kinect_agent.formats import ui_prmd, ui_prmd_vicon  # noqa: E402
from kinect_agent.processing.config import PipelineConfig  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402

METHODS = ("offline", "online")


def squared_errors(pair: om.Pair, config: PipelineConfig) -> dict[str, np.ndarray]:
    """Returns {method: (T, J) squared error m², NaN where not scored} of one accepted pair."""
    out = {}
    for method in METHODS:
        est = process(pair.kinect, online=method == "online", config=config).filtered.positions
        truth = om.register(est, pair.vicon, pair.joints)
        out[method] = np.sum((est - truth) ** 2, axis=-1)
    return out


def _rmse_mm(squared: list[np.ndarray]) -> np.ndarray:
    """Returns (J,) mm: the RMSE per joint pooled over the episodes' squared errors (T, J) m²; NaN if never scored."""
    sq = np.concatenate(squared)
    n = np.sum(np.isfinite(sq), axis=0)
    return 1e3 * np.sqrt(np.nansum(sq, axis=0) / np.where(n > 0, n, np.nan))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, nargs="+", default=[1])
    parser.add_argument("--episodes", type=int, nargs="+", default=list(range(1, 11)))
    parser.add_argument("--set", nargs="*", default=[], help="PipelineConfig overrides NAME=VALUE")
    args = parser.parse_args(argv)
    config = PipelineConfig(**{k: ast.literal_eval(v) for k, v in (s.split("=", 1) for s in args.set)})
    joints = joint_mask(om.UI_JOINTS)
    total: dict[str, list[np.ndarray]] = {m: [] for m in METHODS}
    lost_rows, accepted, tried = 0, 0, 0
    print(f"offline vs online per joint, UI-PRMD s{args.subjects} e{args.episodes}, overrides {args.set or 'none'}")
    for move in range(1, 11):
        errs: dict[str, list[np.ndarray]] = {m: [] for m in METHODS}
        for s in args.subjects:
            for e in args.episodes:
                name = f"m{move:02d}_s{s:02d}_e{e:02d}_positions.txt.gz"
                k_path, v_path = (
                    om.UI_DIR / "Segmented Movements" / d / "Positions" / name for d in ("Kinect", "Vicon")
                )
                if not (k_path.is_file() and v_path.is_file()):
                    continue
                tried += 1
                pair = om.make_pair(name, "UI-PRMD", f"m{move:02d}", ui_prmd.read(k_path), ui_prmd_vicon.read(v_path),
                                    joints, check=True)  # fmt: skip
                if not pair.accepted:
                    continue
                accepted += 1
                for m, v in squared_errors(pair, config).items():
                    errs[m].append(v)
        if not errs["offline"]:
            continue
        rmse = {m: _rmse_mm(v) for m, v in errs.items()}
        for m in METHODS:
            total[m] += errs[m]
        worse = [j for j in range(skeleton.J) if joints[j] and rmse["offline"][j] > rmse["online"][j]]
        lost_rows += bool(worse)
        lost = ", ".join(f"{skeleton.JOINTS[j]} {rmse['offline'][j]:.1f}>{rmse['online'][j]:.1f}" for j in worse)
        print(f"  m{move:02d} ({len(errs['offline'])} episodes): offline {np.nanmean(rmse['offline'][joints]):.1f} "
              f"online {np.nanmean(rmse['online'][joints]):.1f} mm (mean over joints); loses at: {lost or 'none'}",
              flush=True)  # fmt: skip
    rmse = {m: _rmse_mm(v) for m, v in total.items()}
    print(f"{accepted} of {tried} episodes accepted; {lost_rows} movements with a joint where offline > online")
    per_joint = [
        f"{skeleton.JOINTS[j]} {rmse['offline'][j]:.1f}/{rmse['online'][j]:.1f}" for j in np.flatnonzero(joints)
    ]
    print("all movements, per joint (offline / online mm): " + ", ".join(per_joint))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
