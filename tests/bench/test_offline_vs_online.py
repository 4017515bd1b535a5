"""bench/offline_vs_online.py's report of the property "offline ≤ online + tolerance at every joint of every row"."""

import numpy as np

from bench import offline_vs_online as ovo
from kinect_agent import skeleton


def _row(motion: str, margins: dict[str, float], seed: int = 1) -> ovo.Row:
    online = np.full(skeleton.J, 50.0)
    offline = online.copy()
    for name, margin in margins.items():
        offline[skeleton.INDEX[name]] += margin
    return ovo.Row(motion, 0, seed, offline, online)


def test_a_joint_loses_only_beyond_the_tolerance() -> None:
    row = _row("kick", {"FOO_L": 0.5, "ANK_L": 3.0, "HAN_R": -4.0})
    assert [skeleton.JOINTS[j] for j in row.lost(0.0)] == ["ANK_L", "FOO_L"]
    assert [skeleton.JOINTS[j] for j in row.lost(1.0)] == ["ANK_L"]


def test_summary_counts_rows_pairs_and_names_the_worst_margin() -> None:
    rows = [_row("kick", {"ANK_L": 3.0, "FOO_L": 2.0}), _row("sim_side_step", {"KNE_L": 0.4}, seed=2),
            _row("cmu_Twist", {"HAN_L": -5.0})]  # fmt: skip
    text = ovo.summary(rows, 1.0)
    assert text.startswith("1 of 3 rows lose at some joint by > 1 mm, 2 (row, joint) pairs"), text
    assert "worst margin +3.0 mm (kick 0° seed 1 ANK_L: 53.0 vs 50.0)" in text, text


def test_sources_and_markdown_cells() -> None:
    assert [ovo.source_of(m) for m in ("kick", "cmu_Twist", "sim_squat")] == ["hdm05", "cmu", "sim"]
    table = ovo.markdown([_row("kick", {"ANK_L": 3.0}), _row("kick", {"ANK_L": -2.0}, seed=2)], 0.0)
    assert "| kick | 1 / +3.0 | 0 / +0.0 |" in table, table
