"""Compiled (numba) element-wise loops of the BDF step's hot path, loaded lazily.

Each loop performs, element by element, the very operations of the numpy code it
replaces in ``bdf.NordsieckBDF`` (same operands, same order, one IEEE rounding per
operation; numba without fastmath neither reassociates nor fuses a multiply and an
add), so the results are bit-identical to it (tests/test_solver_kernels.py) and no
decision of the solver changes. What they save is numpy's per-call overhead: on
this machine a numpy operation on a few elements costs 0.6 to 1 us, a compiled call
with the same arguments about 1 us for the whole loop. Reductions (the dot products
of the norms) stay in numpy: BLAS's ddot sums in its own order.

``newton_update`` (one modified-Newton update, after the LU solve x = J^-1 F):

    d = -x * scale                  [unit of y]  (scale 2 / (1 + cj / cj_J), or 1)
    y_new = y + d,  yp_new = yp + cj * d,  dw = d * w    (w: weights, 1 / unit of y)

for the numpy lines ``d = solve(-f); d *= scale; y + d; yp + cj * d; d * weights``
(solve(-f) == -solve(f) to the bit: every operation of the LU solve is odd in the
right-hand side).

``weights``: w = 1 / (rtol |y| + atol)   [1 / unit of y]

The module imports numba; ``bdf`` loads it only when numba is already loaded in the
process (water plants load it for IF97) or when a run without a sparsity pattern has
taken ``bdf.KERNELS_AFTER_STEPS`` steps: importing numba and loading the cached
loops costs about 0.3 s of CPU once per process, and a plant of ideal gases never
pays it.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def newton_update(x, scale, y, yp, cj, w, y_new, yp_new, dw):
    """Fill y_new, yp_new and dw from the solve x = J^-1 F (formulas above)."""
    for i in range(x.size):
        d = -x[i]
        if scale != 1.0:
            d = d * scale
        y_new[i] = y[i] + d
        yp_new[i] = yp[i] + cj * d
        dw[i] = d * w[i]


@numba.njit(cache=True, nogil=True)
def weights(y, rtol, atol, out):
    """out = 1 / (rtol |y| + atol), atol an array of y's size."""
    for i in range(y.size):
        out[i] = 1.0 / (rtol * abs(y[i]) + atol[i])
    return out


def warm() -> None:
    """Compile or load every loop (so the first step does not pay for it)."""
    a = np.ones(2)
    newton_update(a, 0.5, a, a, 1.0, a, np.empty(2), np.empty(2), np.empty(2))
    weights(a, 1e-6, a, np.empty(2))
