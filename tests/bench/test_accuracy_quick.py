"""bench/accuracy.py --quick: runs end to end, has the documented structure, and the pipeline beats raw."""

import copy
import json
from typing import Any

import pytest

from bench import accuracy


@pytest.fixture(scope="module")
def results(quick_accuracy: dict[str, Any]) -> dict[str, Any]:
    """The quick run's results file (tests/bench/conftest.py), a copy: a test that edits it leaves the others' alone."""
    return copy.deepcopy(quick_accuracy)


@pytest.mark.shared_data
def test_structure(results: dict[str, Any]) -> None:
    assert results["quick"] is True
    assert results["mocap"] == ["cmu_13_29"], "CMU 13_29 from ../shared/data must be part of the quick run"
    (setting,) = results["settings"]
    assert (setting["device"], setting["view_deg"]) == ("kinect2", 30)
    for table in (setting["methods"], results["summary"]["methods"]):
        assert set(table) == set(accuracy.METHODS)
        for name, m in table.items():
            for key in ("rmse_mm", "rmse_loss_mm", "rmse_debiased_mm", "segment_sd_mm", "angle_rmse_deg"):
                assert m[key] is not None and m[key] >= 0, f"{name}.{key} = {m[key]!r}"
    off = setting["methods"]["pipeline_offline"]
    assert 0.0 <= off["precision"] <= 1.0 and 0.0 <= off["recall"] <= 1.0
    assert setting["methods"]["raw"]["precision"] is None, "baselines do not flag outliers"
    gain = setting["gain"]["standing"]
    assert set(gain) == {"paper_mean_pct", "paper_sd_pct", "mean_pct", "sd_pct", "oracle_mean_pct", "oracle_sd_pct"}
    assert gain["paper_sd_pct"] == 46.0, "Kinect 2, standing, 30°: the paper's SD gain"
    for targets in (setting["targets"], results["summary"]["targets"]):
        assert set(targets) == {"rmse", "segment_sd", "angles", "outliers", "gain"}
        assert all(isinstance(t["pass"], bool) and t["detail"] for t in targets.values())


@pytest.mark.shared_data
def test_pipeline_beats_raw(results: dict[str, Any]) -> None:
    m = results["summary"]["methods"]
    for name in ("pipeline_offline", "pipeline_online"):
        assert m["raw"]["rmse_mm"] > m[name]["rmse_mm"], f"raw {m['raw']['rmse_mm']:.1f} mm vs {name}"
        assert m["raw"]["rmse_loss_mm"] > 2 * m[name]["rmse_loss_mm"], "tracking-loss frames must be repaired"


@pytest.mark.shared_data
def test_readme_tables_from_the_results_file(results: dict[str, Any], tmp_path, capsys) -> None:
    from bench import accuracy_tables

    path = tmp_path / "quick.json"
    path.write_text(json.dumps(results))
    assert accuracy_tables.main([str(path)]) == 0
    out = capsys.readouterr().out
    rmse = results["settings"][0]["methods"]["pipeline_offline"]["rmse_mm"]
    assert "| kinect2 30° | " in out and f"| {rmse:.1f} |" in out
    assert out.count("| **pooled** |") == 6, "five metric tables and the outlier table"
    path.write_text("{}")
    assert accuracy_tables.main([str(path)]) == 2
    assert "not a bench/accuracy.py results file" in capsys.readouterr().err
