"""The paper's accuracy tables (Wang et al., section 3.1) computed from measured pairs, in its layout, as CSV.

Pairs are grouped by (pose, view); one table per pose and stage, one column pair per view:
    tables 1-2  joint_offset_<pose>_<stage>_mm.csv: joint, mean_<view>, sd_<view> of the offset distance (mm)
    tables 3-4  bone_length_error_<pose>_<stage>_mm.csv: segment, mean_<view>, sd_<view> of estimate minus mocap
                segment length (mm)
    table 5     outlier_removal_gain_pct.csv: removal (mixture = the paper's; pipeline = the pipeline's own flags),
                pose, mean_gain_<view>, sd_gain_<view>: % lower offset mean and SD after removal, averaged over joints
    error_parts_mm.csv: stage, joint, rmse_mm, bias_mm (RMS over pairs of each pair's mean error in the body frame),
                random_mm (the rest), n
Statistics pool every counted joint-frame of the group's pairs; a joint or segment without any is left empty.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from kinect_agent import skeleton
from kinect_agent.evaluation.error_parts import JointErrorSums
from kinect_agent.evaluation.measure import STAGES, PairErrors

Table = list[dict[str, object]]


def _view_key(view: float) -> str:
    return f"{view:g}"


def groups(errors: list[PairErrors]) -> dict[tuple[str, str], list[PairErrors]]:
    """Returns the pairs by (pose, view as text), in a stable order."""
    out: dict[tuple[str, str], list[PairErrors]] = {}
    for e in errors:
        out.setdefault((e.pair.spec.pose, _view_key(e.pair.spec.view_deg)), []).append(e)
    return dict(sorted(out.items(), key=lambda kv: (kv[0][0], float(kv[0][1]))))


def _stats_mm(values: np.ndarray) -> tuple[float | None, float | None]:
    v = values[np.isfinite(values)]
    return (None, None) if v.size == 0 else (1e3 * float(v.mean()), 1e3 * float(v.std()))


def _pooled(errors: list[PairErrors], stage: str, kind: str) -> np.ndarray:
    """Returns (N, K) m: distances (kind "offset", K = J) or segment errors ("bone", K = 14) of every pair stacked."""
    parts = [e.distance(stage) if kind == "offset" else e.segment_error(stage) for e in errors]
    return np.concatenate(parts, axis=0)


def layout_table(errors: list[PairErrors], pose: str, stage: str, kind: str) -> Table:
    """Returns tables 1-4: one row per joint (kind "offset") or segment ("bone"), mean and SD columns per view."""
    names = skeleton.JOINTS if kind == "offset" else skeleton.SEGMENT_NAMES
    by_view = {view: _pooled(es, stage, kind) for (p, view), es in groups(errors).items() if p == pose}
    rows: Table = []
    for i, name in enumerate(names):
        row: dict[str, object] = {"joint" if kind == "offset" else "segment": name}
        stats = {view: _stats_mm(x[:, i]) for view, x in by_view.items()}
        row.update({f"mean_{view}": m for view, (m, _) in stats.items()})
        row.update({f"sd_{view}": s for view, (_, s) in stats.items()})
        rows.append(row)
    return rows


def _gain_pct(before: np.ndarray, after: np.ndarray) -> tuple[float, float] | None:
    b, a = before[np.isfinite(before)], after[np.isfinite(after)]
    if b.size < 2 or a.size < 2 or b.mean() == 0 or b.std() == 0:
        return None
    return 100.0 * (1.0 - a.mean() / b.mean()), 100.0 * (1.0 - a.std() / b.std())


def joint_gains(errors: list[PairErrors], removal: str) -> list[tuple[float, float] | None]:
    """Returns per joint (J,) the (mean %, SD %) gain of removing outliers ("mixture" or "pipeline") from raw."""
    before = _pooled(errors, "raw", "offset")
    if removal == "mixture":
        after = _pooled(errors, "clean", "offset")
    else:
        after = np.where(np.concatenate([e.pipeline_flags for e in errors]), np.nan, before)
    return [_gain_pct(before[:, j], after[:, j]) for j in range(before.shape[1])]


def gain_table(errors: list[PairErrors]) -> Table:
    """Returns table 5: per removal and pose, the gain in offset mean and SD (%) averaged over joints, per view."""
    rows: Table = []
    for removal in ("mixture", "pipeline"):
        for pose in sorted({p for p, _ in groups(errors)}):
            row: dict[str, object] = {"removal": removal, "pose": pose}
            for (p, view), es in groups(errors).items():
                if p != pose:
                    continue
                g = [x for x in joint_gains(es, removal) if x is not None]
                row[f"mean_gain_{view}"] = float(np.mean([x[0] for x in g])) if g else None
                row[f"sd_gain_{view}"] = float(np.mean([x[1] for x in g])) if g else None
            rows.append(row)
    return rows


def error_parts_table(errors: list[PairErrors]) -> Table:
    """Returns per stage and joint the RMSE and its bias and random parts (mm), over every pair."""
    rows: Table = []
    for stage in STAGES:
        sums = JointErrorSums.zeros(skeleton.J)
        for e in errors:
            sums.add(e.estimates[stage], e.truth, e.mocap)
        parts = sums.rms_mm()
        for j, name in enumerate(skeleton.JOINTS):
            if parts["n"][j]:
                rows.append({"stage": stage, "joint": name, **{k: _num(v[j]) for k, v in parts.items()}})
    return rows


def _num(x: float | np.integer) -> float | int:
    return int(x) if isinstance(x, np.integer) else float(x)


def all_tables(errors: list[PairErrors]) -> dict[str, Table]:
    """Returns every table by its CSV file name."""
    out: dict[str, Table] = {}
    for pose in sorted({p for p, _ in groups(errors)}):
        for stage in STAGES:
            out[f"joint_offset_{pose}_{stage}_mm.csv"] = layout_table(errors, pose, stage, "offset")
            out[f"bone_length_error_{pose}_{stage}_mm.csv"] = layout_table(errors, pose, stage, "bone")
    out["outlier_removal_gain_pct.csv"] = gain_table(errors)
    out["error_parts_mm.csv"] = error_parts_table(errors)
    return out


def write_csv(rows: Table, path: Path) -> None:
    """Writes rows (same keys) as CSV; None becomes an empty cell, numbers get 1 decimal."""
    fields = list(rows[0]) if rows else []
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({k: "" if v is None else f"{v:.1f}" if isinstance(v, float) else v for k, v in r.items()})
