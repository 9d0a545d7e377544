"""One BLAS thread for simulations, unless the user chose a number.

A plant's linear algebra is a band or sparse LU of a few hundred to tens of
thousands of unknowns, and the solver's error norms are BLAS dot products
(``dnasim.solver.kernels``). A BLAS thread pool does not make these faster, but
its workers spin after every call they took part in, and that is CPU time taken
from other work on the machine (and, in a sweep, from the other Dask workers,
the over-subscription dask's documentation warns of). Measured on 2 cores:

- ``dnasim run`` of a small plant: numpy's and scipy's bundled OpenBLAS copies
  each make a pool at import; 0.2 to 0.3 s of a 1 s run's CPU, no gain in wall time.
- the 3000-volume pipe (21015 unknowns) through ``solve_dae``: OpenBLAS splits a
  dot product over its threads above 10000 elements, and the idle worker then
  spins between steps: 13.9 s of CPU for 7.1 s of work. The 1000-volume pipe
  (7015 unknowns): 0.017 to 0.027 CPU s per simulated second in 5 processes,
  0.017 to 0.0195 with one thread.

Two ways, one rule (the user's setting wins):

- :func:`single_threaded_environment`: the command line sets
  ``OPENBLAS_NUM_THREADS=1`` (and MKL's and Accelerate's) before numpy is imported,
  so no pool is made (``dnasim.cli.entry``). Child processes (a sweep's Dask workers)
  inherit it.
- :func:`one_blas_thread`: ``solve_dae`` limits the BLAS libraries already loaded to
  one thread while it integrates a system of at least :data:`MIN_UNKNOWNS` unknowns
  (threadpoolctl, 0.8 ms to set and restore: a visible cost on a small problem that
  solves in a few ms, nothing on a large one), unless one of the variables is set.

This module imports neither numpy nor threadpoolctl at import time.
"""

from __future__ import annotations

import contextlib
import os

__all__ = [
    "MIN_UNKNOWNS",
    "THREAD_VARIABLES",
    "one_blas_thread",
    "single_threaded_environment",
    "user_has_chosen",
]

#: The BLAS libraries' thread-count variables (OpenBLAS, which numpy's and scipy's
#: wheels bundle; MKL; Apple's Accelerate).
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "VECLIB_MAXIMUM_THREADS")

#: ``solve_dae`` limits the BLAS threads from this many unknowns on: a run of a system
#: this size takes a tenth of a second or more, so the limit's 0.8 ms does not show,
#: and from about 7000 unknowns on the pools measurably cost CPU (module doc)
MIN_UNKNOWNS = 1000


def user_has_chosen(environ=os.environ) -> bool:
    """True when one of :data:`THREAD_VARIABLES` is set in ``environ``."""
    return any(name in environ for name in THREAD_VARIABLES)


def single_threaded_environment(environ=os.environ) -> None:
    """Set each of :data:`THREAD_VARIABLES` to 1 that the user has not set. Works only
    before numpy is imported (the pools are made at import)."""
    for name in THREAD_VARIABLES:
        environ.setdefault(name, "1")


def one_blas_thread(n: int, environ=os.environ):
    """A context manager: the loaded BLAS libraries run one thread inside it, when a
    system of n unknowns is large enough for that to matter (:data:`MIN_UNKNOWNS`) and
    the user has not set a thread count; otherwise it does nothing."""
    if n < MIN_UNKNOWNS or user_has_chosen(environ):
        return contextlib.nullcontext()
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")
