"""bench/worst_file.py's parts (no server): the file is what its docstring says, and ProcessMeter reads another
process's CPU time and peak memory."""

import subprocess
import sys
import time

import numpy as np

from bench.worst_file import OUTLIER_SHARE, ProcessMeter, worst_file
from kinect_agent.formats import session_file as sf

BURN = "import time\nx = bytearray(200 * 2**20)\nfor i in range(0, len(x), 4096): x[i] = 1\nt = time.process_time()\n" \
       "while time.process_time() - t < 0.5: pass\ntime.sleep(30)"  # fmt: skip


def test_worst_file_spreads_its_frames_over_the_duration_with_noise_and_outliers():
    payload = sf.decode(worst_file(3000, 100.0), max_frames=3000, max_decoded_bytes=2**26)
    assert payload.filtered is not None
    assert payload.raw.n_frames == payload.filtered.n_frames == 3000
    np.testing.assert_allclose(payload.raw.duration, 100.0 * 2999 / 3000, rtol=1e-6)
    error = np.linalg.norm(payload.raw.positions - payload.filtered.positions, axis=2)  # (T, J) m, NaN = untracked
    assert 0.02 < float(np.nanmedian(error)) < 0.06, "2 cm per axis: about 3 cm per joint"
    thrown = np.mean((np.nan_to_num(error) > 0.2).any(axis=1))
    assert 0.5 * OUTLIER_SHARE < thrown <= OUTLIER_SHARE * 1.5, f"{thrown:.3f} of frames with an outlier"


def test_process_meter_reads_another_process_cpu_and_peak_memory():
    child = subprocess.Popen([sys.executable, "-c", BURN])
    try:
        meter = ProcessMeter(child.pid)
        meter.start()
        time.sleep(3.0)
        cpu, peak = meter.stop()
    finally:
        child.kill()
        child.wait()
    assert 0.4 <= cpu < 3.0, f"CPU {cpu:.2f} s"
    assert peak > 100 * 2**20, f"peak {peak / 2**20:.0f} MiB"
