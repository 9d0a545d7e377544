"""One BLAS thread for simulations unless the user chose a number (``dnasim.core.blas_threads``).

The command line's setting only works if it is in the environment before numpy is
imported (the OpenBLAS pools are made at import), so the tests check the value, that
a user's choice wins, and that the entry module imports no numpy before ``main`` sets
it; ``solve_dae``'s limit is checked from inside a residual of a large system.
"""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse

from dnasim.core.blas_threads import (
    MIN_UNKNOWNS,
    THREAD_VARIABLES,
    one_blas_thread,
    single_threaded_environment,
)


def test_unset_variables_get_one_thread():
    env = {}
    single_threaded_environment(env)
    assert env == {name: "1" for name in THREAD_VARIABLES}


def test_a_users_choice_is_kept():
    env = {"OPENBLAS_NUM_THREADS": "4"}
    single_threaded_environment(env)
    assert env["OPENBLAS_NUM_THREADS"] == "4"
    assert env["MKL_NUM_THREADS"] == "1"


def test_numpy_is_imported_after_the_setting():
    # a fresh interpreter: importing the entry point must not import numpy (else the
    # pools exist before main() sets the variables), and a run of the command line
    # (here `dnasim --version`, with numpy imported afterwards in the same process)
    # sees the variable in its environment
    code = (
        "import os, sys\n"
        "import dnasim.cli.entry as e\n"
        "assert 'numpy' not in sys.modules, 'numpy imported with dnasim.cli.entry'\n"
        "e.main(['--version'])\n"
        "import numpy\n"
        "print(os.environ['OPENBLAS_NUM_THREADS'])\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    )
    assert out.stdout.strip().splitlines()[-1] == "1"


def _blas_threads():
    from threadpoolctl import threadpool_info

    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]


def test_limit_only_for_large_systems_and_without_a_user_setting():
    env = {}
    assert isinstance(one_blas_thread(MIN_UNKNOWNS - 1, env), type(one_blas_thread(10, env)))
    with one_blas_thread(MIN_UNKNOWNS, env):
        assert set(_blas_threads()) <= {1}
    with one_blas_thread(MIN_UNKNOWNS, {"OPENBLAS_NUM_THREADS": "2"}):
        pass  # nothing set: the user's variable wins (no threadpoolctl call to check)


def test_solve_dae_runs_a_large_system_with_one_blas_thread(monkeypatch):
    # y' = -y for MIN_UNKNOWNS unknowns; the residual records the BLAS thread counts
    # it sees. Without a thread pool (a 1-core machine) there is nothing to limit.
    for name in THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    if not _blas_threads() or max(_blas_threads()) < 2:
        pytest.skip("the BLAS libraries here run one thread anyway")
    from dnasim.solver import solve_dae

    n = MIN_UNKNOWNS
    seen = []

    def F(t, y, yp):
        if not seen:
            seen.extend(_blas_threads())
        return yp + y

    pattern = scipy.sparse.identity(n, format="csr")
    res = solve_dae(
        F, (0.0, 0.01), np.ones(n), -np.ones(n), jac_sparsity=pattern, calc_initial=False
    )
    assert res.success
    assert seen and set(seen) == {1}
    assert max(_blas_threads()) >= 2  # restored afterwards
