"""Prints the per-metric tables of bench/README.md (settings as rows, methods as columns) from a results file.

Usage, from the repository root:
    .venv/bin/python bench/accuracy.py --json acc.json
    .venv/bin/python bench/accuracy_tables.py acc.json
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

METRICS = (  # (results key, title, digits)
    ("rmse_mm", "Joint RMSE, mm (every joint-frame, 3-D)", 1),
    ("rmse_debiased_mm",
     "Joint RMSE after removing each joint's mean error per recording, mm (what filtering can reach)", 1),
    ("bias_mm", "Bias (RMS of each joint's mean error), mm", 1),
    ("segment_sd_mm", "Segment-length SD, mm", 2),
    ("angle_rmse_deg", "Elbow/knee flexion RMSE, degrees", 2),
)  # fmt: skip
SOURCE_ROLE = {"cmu": "tuning", "hdm05": "held out", "simulator": "tuning"}


def cell(v: float | None, digits: int = 1) -> str:
    """Returns a table cell: v with `digits` decimals, or "—" when there is no value."""
    return "—" if v is None else f"{v:.{digits}f}"


def rows(results: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    """Returns [(row label, {method: metrics})]: each setting, pooled, then pooled per source."""
    out = [(f"{s['device']} {s['view_deg']}°", s["methods"]) for s in results["settings"]]
    out.append(("**pooled**", results["summary"]["methods"]))
    for src, table in results["summary"]["by_source"].items():
        out.append((f"pooled, {src} only ({SOURCE_ROLE.get(src, '')})", table))
    return out


def metric_table(results: dict[str, Any], key: str, digits: int) -> list[str]:
    """Returns the markdown lines of one metric's table."""
    table_rows = rows(results)
    methods = list(table_rows[0][1])
    lines = ["| setting | " + " | ".join(methods) + " |", "|---" * (len(methods) + 1) + "|"]
    for label, metrics in table_rows:
        lines.append(f"| {label} | " + " | ".join(cell(metrics[m][key], digits) for m in methods) + " |")
    return lines


def _gain_cell(g: dict[str, Any] | None) -> str:
    if g is None or g.get("mean_pct") is None:
        return "—"
    return (f"{g['mean_pct']:.1f} / {g['sd_pct']:.1f} ({g['oracle_mean_pct']:.1f} / {g['oracle_sd_pct']:.1f}; "
            f"{g['paper_mean_pct']:.0f} / {g['paper_sd_pct']:.0f})")  # fmt: skip


def outlier_table(results: dict[str, Any]) -> list[str]:
    """Returns the markdown lines of the outlier table: precision, recall and the paper's gain per setting."""
    lines = ["| setting | precision | precision incl. gross jumps | recall | gain standing mean/SD % (oracle; paper) "
             "| gain sitting mean/SD % (oracle; paper) |", "|---|---|---|---|---|---|"]  # fmt: skip
    for s in results["settings"]:
        m = s["methods"]["pipeline_offline"]
        gains = [_gain_cell(s["gain"].get(pose)) for pose in ("standing", "sitting")]
        lines.append(f"| {s['device']} {s['view_deg']}° | {m['precision']:.3f} | {m['precision_incl_gross']:.3f} | "
                     f"{m['recall']:.3f} | {gains[0]} | {gains[1]} |")  # fmt: skip
    m = results["summary"]["methods"]["pipeline_offline"]
    lines.append(f"| **pooled** | {m['precision']:.3f} | {m['precision_incl_gross']:.3f} | {m['recall']:.3f} | | |")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("results", help="JSON written by bench/accuracy.py --json")
    args = parser.parse_args(argv)
    try:
        with open(args.results, encoding="utf-8") as f:
            results = json.load(f)
        blocks = [[f"**{title}**", "", *metric_table(results, key, digits)] for key, title, digits in METRICS]
        blocks.append(["**Outlier detection (pipeline offline) and the paper's gain**", "", *outlier_table(results)])
    except (OSError, ValueError, KeyError, TypeError) as exc:
        print(f"accuracy_tables.py: {args.results}: not a bench/accuracy.py results file ({exc})", file=sys.stderr)
        return 2
    print("\n\n".join("\n".join(b) for b in blocks))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
