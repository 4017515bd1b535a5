"""Runs the evaluation of several Kinect/mocap pairs and writes report.md, the tables as CSV, figures as PNG and
summary.json into one folder."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from kinect_agent import skeleton
from kinect_agent.errors import AgentError
from kinect_agent.evaluation import figures, tables
from kinect_agent.evaluation.align import MAX_LAG_S
from kinect_agent.evaluation.measure import PairErrors, measure
from kinect_agent.evaluation.pairs import PairRefused, PairSpec, make_pair
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.sources.kinect_noise import VIEWS, load_tables

ANGLE_FIGURES = 3  # figure 4 is drawn for the first pairs only


class NothingAligned(AgentError):
    """Every pair was refused; the report lists why."""


@dataclass(frozen=True)
class Outcome:
    """What an evaluation produced: the measured pairs, the refused ones and the summary written."""

    errors: list[PairErrors]
    refused: list[PairRefused]
    summary: dict[str, Any]


def pair_summary(e: PairErrors) -> dict[str, Any]:
    """Returns one aligned pair's alignment numbers (JSON-ready)."""
    p, al = e.pair, e.pair.alignment
    d = e.distance("raw")
    return {
        "name": p.spec.name, "kinect": str(p.spec.kinect), "mocap": str(p.spec.mocap),
        "view_deg": p.spec.view_deg, "pose": p.spec.pose,
        "kinect_frames": p.kinect.n_frames, "mocap_frames": p.mocap.n_frames, "overlap_frames": int(p.overlap.sum()),
        "scored_joints": [j for j, s in zip(skeleton.JOINTS, p.joints, strict=True) if s],
        "lag_s": al.lag_s, "lag_xcorr_s": al.lag_xcorr_s, "xcorr": al.xcorr, "lag_rms_s": al.lag_rms_s,
        "lag_halves_s": list(al.lag_halves_s), "rotation_deg": al.registration.rotation_deg(),
        "translation_m": al.registration.t.tolist(), "registration_rms_mm": 1e3 * al.registration.rms_m,
        "raw_offset_median_mm": 1e3 * float(np.nanmedian(d)) if np.isfinite(d).any() else None,
    }  # fmt: skip


def evaluate(specs: list[PairSpec], out: Path, *, config: PipelineConfig | None = None, rigid: bool = True,
             max_lag_s: float = MAX_LAG_S, draw: bool = True) -> Outcome:  # fmt: skip
    """Evaluates every pair, writes the report into `out`; raises NothingAligned (after writing) when all are
    refused. FormatError (bad file) stops the run before anything is written."""
    config = config or PipelineConfig()
    if draw:
        figures.pyplot()  # fail before the work when matplotlib is missing
    errors, refused = [], []
    for spec in specs:
        try:
            errors.append(measure(make_pair(spec, max_lag_s=max_lag_s, rigid=rigid), config))
        except PairRefused as exc:
            refused.append(exc)
    out.mkdir(parents=True, exist_ok=True)
    written = {}
    if errors:
        for name, rows in tables.all_tables(errors).items():
            tables.write_csv(rows, out / name)
            written[name] = rows
    pngs = draw_figures(errors, out, config) if draw and errors else []
    summary = {
        "pairs": [pair_summary(e) for e in errors],
        "refused": [{"name": r.name, "reasons": r.reasons} for r in refused],
        "registration": "rigid (Kabsch)" if rigid else "none (mocap given in the Kinect camera frame)",
        "tables": written,
        "figures": pngs,
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=_json_default), encoding="utf-8")
    (out / "report.md").write_text(markdown(summary), encoding="utf-8")
    if not errors:
        raise NothingAligned(f"every pair was refused ({len(refused)}); see {out / 'report.md'}: "
                             + " | ".join(str(r) for r in refused))  # fmt: skip
    return Outcome(errors, refused, summary)


def _json_default(x: object) -> object:
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(f"not JSON: {type(x).__name__}")


def draw_figures(errors: list[PairErrors], out: Path, config: PipelineConfig) -> list[str]:
    """Draws figure 3 (pooled) and figure 4 (first pairs); returns the PNG file names."""
    names = ["figure3_mixture.png"]
    figures.mixture_figure(errors, out / names[0], config)
    for i, e in enumerate(errors[:ANGLE_FIGURES]):
        name = f"figure4_angles_{i + 1}.png"
        if figures.angle_figure(e, out / name):
            names.append(name)
    return [n for n in names if (out / n).is_file()]


def _md_table(rows: list[dict[str, Any]]) -> list[str]:
    if not rows:
        return ["(empty)"]
    keys = list(rows[0])

    def cell(v: object) -> str:
        return "—" if v is None else f"{v:.1f}" if isinstance(v, float) else str(v)

    return ["| " + " | ".join(keys) + " |", "|---" * len(keys) + "|",
            *("| " + " | ".join(cell(r[k]) for k in keys) + " |" for r in rows)]  # fmt: skip


def with_paper(name: str, rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Returns the rows of a table 1-4 with the paper's Kinect 2 mean and SD (mm) beside each tabled view
    (kinect_agent/sources/calibration: the paper's tables); other tables unchanged."""
    kind = "offset" if name.startswith("joint_offset_") else "bone" if name.startswith("bone_length_error_") else None
    if kind is None or not rows:
        return rows
    pose = name.split("_")[2 if kind == "offset" else 3]
    tables = load_tables()
    names = list(skeleton.JOINTS if kind == "offset" else skeleton.SEGMENT_NAMES)
    out = [dict(r) for r in rows]
    for key in [k for k in rows[0] if k.startswith("sd_")]:
        view = key[3:]
        setting = ("kinect2", pose, int(float(view))) if float(view) in VIEWS else None
        if setting is None:
            continue
        mean = (tables.offset_mean if kind == "offset" else tables.bone_mean)[setting]
        sd = (tables.offset_sd if kind == "offset" else tables.bone_sd)[setting]
        for r in out:
            i = names.index(r["joint" if kind == "offset" else "segment"])
            r[f"paper_k2_mean_{view}"], r[f"paper_k2_sd_{view}"] = 1e3 * float(mean[i]), 1e3 * float(sd[i])
    return out


def markdown(summary: dict[str, Any]) -> str:
    """Returns report.md: alignment per pair, refused pairs, every table (tables 1-4 with the paper's Kinect 2
    numbers beside ours) and the figures."""
    lines = ["# Kinect accuracy against motion capture", "",
             f"Registration: {summary['registration']}. Lag: mocap time = Kinect time + lag.", "",
             "## Pairs", "", "| pair | pose | view ° | frames K / mocap | lag s (speed r) | lag by RMS s | "
             "reg. residual mm | rotation ° |", "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for p in summary["pairs"]:
        lag_rms = "—" if p["lag_rms_s"] is None else f"{p['lag_rms_s']:+.3f}"
        lines.append(f"| {p['name']} | {p['pose']} | {p['view_deg']:g} | {p['kinect_frames']} / {p['mocap_frames']} | "
                     f"{p['lag_s']:+.3f} ({p['xcorr']:.2f}) | {lag_rms} | {p['registration_rms_mm']:.1f} | "
                     f"{p['rotation_deg']:.1f} |")  # fmt: skip
    if summary["refused"]:
        lines += ["", "## Refused pairs", ""]
        lines += [f"- {r['name']}: {'; '.join(r['reasons'])}" for r in summary["refused"]]
    for name, rows in summary["tables"].items():
        lines += ["", f"## {name}", "", *_md_table(with_paper(name, rows))]
    if summary["figures"]:
        lines += ["", "## Figures", ""]
        lines += [f"![{n}]({n})" for n in summary["figures"]]
    return "\n".join(lines) + "\n"
