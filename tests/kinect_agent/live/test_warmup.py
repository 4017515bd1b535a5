"""warm_up() readies every compiled kernel the live loop runs, in a fresh process, before any set."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from kinect_agent.processing import _ukf_numba

CHILD = """
import json
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
