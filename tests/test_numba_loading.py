"""Cached numba kernels load without numba's compiler set-up (dnasim.media.numba_loading),
and numba still compiles afterwards.

Run in a fresh interpreter: in this test process numba may have compiled something
already, and then its registries are loaded whatever the cache loads do.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

CHILD = r"""
import json, sys
import numpy as np
from dnasim.media import if97_numba as NB
from dnasim.media import numba_loading
from dnasim.media.if97 import IF97Water

water = IF97Water(kernel="numba")
p = np.array([1e5, 5e6, 1.4e7, 2.5e7])
h = np.array([4e5, 2.0e6, 3.3e6, 2.4e6])
# the first calls install the lean loads, then load (or compile) their kernels
out = {"T": water.states(p, h).T.tolist(), "T1": water.state(1e5, 4e5).T}
out["installed"] = numba_loading.installed()
out["hits"] = sum(NB.ph_scalar.stats.cache_hits.values()) + sum(
    NB._ph_branch_loop.stats.cache_hits.values())
out["registries"] = "numba.np.arraymath" in sys.modules
out["T_ref"] = IF97Water(kernel="numpy").states(p, h).T.tolist()

import numba

@numba.njit
def total(x):  # a new compilation: needs the registries the cache loads skipped
    return np.sum(x) * 2.0

out["total"] = total(np.arange(5.0))
out["registries_after"] = "numba.np.arraymath" in sys.modules
print(json.dumps(out))
"""


def test_cached_kernels_load_lean_and_numba_still_compiles():
    pytest.importorskip("numba")
    proc = subprocess.run(
        [sys.executable, "-c", CHILD], capture_output=True, text=True, cwd=str(ROOT), timeout=600
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    if not out["installed"]:
        pytest.skip("numba's internals differ from those numba_loading knows")
    if out["hits"] == 2:
        # both kernels came from the cache: loading them imported none of numba's
        # compiler registries (numba.np.arraymath is one; a full refresh imports it)
        assert not out["registries"]
    # the kernels compute what the numpy kernel computes; the two kernels agree to
    # about 1e-12 (tests/test_if97_kernel.py), so 1e-11 relative
    assert out["T"] == pytest.approx(out["T_ref"], rel=1e-11)
    assert out["T1"] == pytest.approx(out["T_ref"][0], rel=1e-11)
    # a compilation after lean loads gets the full set-up: np.sum(0..4) * 2 = 20
    assert out["total"] == 20.0
    assert out["registries_after"]
