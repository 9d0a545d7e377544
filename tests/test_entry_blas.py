"""The command line's single-threaded BLAS (``dnasim.entry.single_threaded_blas``).

The setting only works if it is in the environment before numpy is imported (the
OpenBLAS pools are made at import), so the tests check the value, that a user's
choice wins, and that the entry module imports no numpy before ``main`` sets it.
"""

from __future__ import annotations

import os
import subprocess
import sys

from dnasim.entry import BLAS_THREAD_VARIABLES, single_threaded_blas


def test_unset_variables_get_one_thread():
    env = {}
    single_threaded_blas(env)
    assert env == {name: "1" for name in BLAS_THREAD_VARIABLES}


def test_a_users_choice_is_kept():
    env = {"OPENBLAS_NUM_THREADS": "4"}
    single_threaded_blas(env)
    assert env["OPENBLAS_NUM_THREADS"] == "4"
    assert env["MKL_NUM_THREADS"] == "1"


def test_numpy_is_imported_after_the_setting():
    # a fresh interpreter: importing the entry point must not import numpy (else the
    # pools exist before main() sets the variables), and a run of the command line
    # (here `dnasim --version`, with numpy imported afterwards in the same process)
    # sees the variable in its environment
    code = (
        "import os, sys\n"
        "import dnasim.entry as e\n"
        "assert 'numpy' not in sys.modules, 'numpy imported with dnasim.entry'\n"
        "e.main(['--version'])\n"
        "import numpy\n"
        "print(os.environ['OPENBLAS_NUM_THREADS'])\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES}
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    )
    assert out.stdout.strip().splitlines()[-1] == "1"
