"""warm_up() readies every compiled kernel the live loop runs, in a fresh process, before any set."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from kinect_agent.processing import _ukf_numba

CHILD = """
import json
import os
from kinect_agent.body import _fk_numba
from kinect_agent.processing import _ukf_numba
before = [len(k.signatures) for k in (_fk_numba.fk_many, _ukf_numba.chain_step, _ukf_numba.add_capped)]
from kinect_agent.live.warmup import warm_up
seconds = warm_up()
after = {name: len(k.signatures) for name, k in (("fk_many", _fk_numba.fk_many), ("chain_step", _ukf_numba.chain_step),
         ("add_capped", _ukf_numba.add_capped))}  # _blas_numba's kernels compile inside chain_step
print(json.dumps({"before": before, "after": after, "seconds": seconds}))
"""


@pytest.mark.skipif(not _ukf_numba.AVAILABLE, reason="numba is not installed (server-only environment)")
def test_warm_up_compiles_the_live_loops_kernels_in_a_fresh_process():
    done = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True, timeout=600, check=True)
    found = json.loads(done.stdout.strip().splitlines()[-1])
    assert found["before"] == [0, 0, 0], "nothing is compiled at import"
    assert all(n >= 1 for n in found["after"].values()), f"kernels left for the first set to compile: {found}"
    assert found["seconds"] > 0


AFTER_PREPARE = """
import json
import os
from kinect_agent.analysis.live import LiveCount
from kinect_agent.live.warmup import WARMUP_ANGLES, cache_folders, kernel_counts
from kinect_agent.processing.online import OnlineFilter
from kinect_agent.processing.pipeline import process
from kinect_agent.sources.simulator import simulate

rec = simulate("squat", 3, seed=5)[0]  # not the warm-up's recording: a first set and a filter of a whole session
online, counter = OnlineFilter(), LiveCount(WARMUP_ANGLES)
for k in range(rec.n_frames):
    t = float(rec.t[k])
    counter.add(t, rec.positions[k], rec.state[k], online.step(t, rec.positions[k], rec.state[k]))
counter.final()
process(rec)
print(json.dumps({**kernel_counts(), "folders": cache_folders()}))
"""


@pytest.mark.skipif(not _ukf_numba.AVAILABLE, reason="numba is not installed (server-only environment)")
def test_prepare_leaves_a_cache_that_a_new_process_loads_without_compiling(tmp_path):
    # an empty cache of the test's own (numba's NUMBA_CACHE_DIR), so that what is found there is what prepare wrote
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    prepared = subprocess.run([sys.executable, "-m", "kinect_agent.cli", "prepare"], env=env, capture_output=True,
                              text=True, timeout=900, check=True)  # fmt: skip
    assert "kernels compiled" in prepared.stderr and str(tmp_path / "numba") in prepared.stderr, prepared.stderr
    done = subprocess.run([sys.executable, "-c", AFTER_PREPARE], env=env, capture_output=True, text=True, timeout=600,
                          check=True)  # fmt: skip
    found = json.loads(done.stdout.strip().splitlines()[-1])
    assert found["cache_misses"] == 0, f"kernels the first set or filter still compiled after prepare: {found}"
    assert found["cache_hits"] >= 5, f"too few kernels loaded from the prepared cache: {found}"
    assert all(folder.startswith(str(tmp_path / "numba")) for folder in found["folders"]), found
