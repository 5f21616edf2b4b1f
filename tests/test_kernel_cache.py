"""The compiled simulator is cached on disk: a new process loads it instead of compiling."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

CODE = """
from posture_id import load_body, simulate
from posture_id.simulation.kernel import kernels
simulate(load_body())
stats = kernels(3).simulate_block.stats
print(sum(stats.cache_hits.values()), sum(stats.cache_misses.values()))
"""


def _run(cache, prebuilt="none") -> tuple[int, int]:
    env = {**os.environ, "POSTURE_ID_CACHE": str(cache), "POSTURE_ID_PREBUILT": str(prebuilt)}
    out = subprocess.run([sys.executable, "-c", CODE], capture_output=True, text=True, env=env)
    assert out.returncode == 0, out.stderr
    hits, misses = (int(x) for x in out.stdout.split())
    # a compile says so on stderr, once; a loaded kernel says nothing
    assert ("compiling the simulator for 3 segment(s)" in out.stderr) == (misses > 0)
    return hits, misses


@pytest.mark.slow("compiles the simulator in a new process")
def test_second_process_loads_the_compiled_kernel(tmp_path):
    hits, misses = _run(tmp_path)
    assert misses >= 1 and hits == 0  # an empty cache: compiled, and saved
    assert any((tmp_path / "kernels").glob("posture_id_kernel_n3_*.py"))
    hits, misses = _run(tmp_path)
    assert hits >= 1 and misses == 0  # a new process: loaded, not compiled


@pytest.mark.slow("compiles the simulator in a new process")
def test_the_prebuilt_kernel_serves_an_empty_cache(tmp_path):
    """The simulator the set-up compiled (the prebuilt folder) is loaded by a process whose
    cache folder is empty: nothing compiled, nothing written there."""
    _run(tmp_path / "setup")  # the set-up's compile
    hits, misses = _run(tmp_path / "new", prebuilt=tmp_path / "setup")
    assert hits >= 1 and misses == 0
    assert not any((tmp_path / "new" / "kernels").glob("*.py"))
