"""Compiled (numba) element-wise loops of the BDF step's hot path, loaded lazily.

Each loop performs, element by element, the very operations of the numpy code it
replaces in ``bdf.NordsieckBDF`` (same operands, same order, one IEEE rounding per
operation; numba without fastmath neither reassociates nor fuses a multiply and an
add), so the results are bit-identical to it (tests/test_solver_kernels.py) and no
decision of the solver changes. What they save is numpy's per-call overhead: on
this machine a numpy operation on a few elements costs 0.6 to 1 us, a compiled call
with the same arguments about 1 us for the whole loop. The dot products of the norms
call BLAS's ddot from the loop (numba's np.dot), the routine numpy calls.

Loops: ``weights``, ``predict`` (P z and y'_pred), ``newton_update`` (and
``newton_update_lu`` with the dense LU solve ``lu_solve_small`` inside), ``correct``
(z = z_pred + l Delta), ``rescale`` (row j times ratio^j), ``wrms`` (the norm) and
``delta_wrms`` (Delta = y - y_pred and its norm), ``wrms_order_errors`` (the two
norms of the order choice in one call).

``newton_update`` (one modified-Newton update, after the LU solve x = J^-1 F):

    d = -x * scale                  [unit of y]  (scale 2 / (1 + cj / cj_J), or 1)
    y_new = y + d,  yp_new = yp + cj * d,  dw = d * w    (w: weights, 1 / unit of y)

for the numpy lines ``d = solve(-f); d *= scale; y + d; yp + cj * d; d * weights``
(solve(-f) == -solve(f) to the bit: every operation of the LU solve is odd in the
right-hand side).

``weights``: w = 1 / (rtol |y| + atol)   [1 / unit of y]

The module imports numba; ``bdf`` loads it only where it pays (``bdf.KERNELS_MIN_N``,
``bdf.KERNELS_AFTER_STEPS_LOADED``, ``bdf.KERNELS_AFTER_STEPS``): with numba already
loaded (water plants load it for IF97) the loops cost about 10 ms of CPU to load from
numba's cache, importing numba first about 0.3 s; a plant of ideal gases never loads
them. Three of them follow a library's summation order rather than numpy's element-wise
rules (``predict``: BLAS's dgemm; ``lu_solve_small``: LAPACK's getrs; the dot products:
BLAS's ddot); each is checked against the library once per process
(``predict_matches_numpy``, ``dense_solve_matches_lapack``, ``dot_matches_numpy``) and
used only where it matches to the bit.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba.core import types
from numba.extending import intrinsic


@intrinsic
def _fma(typingctx, a, b, c):
    """a * b + c with one rounding (LLVM's llvm.fma.f64)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        return builder.fma(*args)

    return sig, codegen


@numba.njit(cache=True, nogil=True)
def predict(pascal, z, q, h, out, yp_out):
    """out[:q+1] = P z[:q+1] and yp_out = out[1] / h [unit of y / time].

    Each entry is summed as BLAS's dgemm kernel sums it (OpenBLAS on x86-64: one
    fused multiply-add per term, j = 0..q, from 0.0), so the products agree with
    numpy's ``pascal @ z[:q+1]`` to the bit where that kernel is the one numpy calls;
    ``predict_matches_numpy`` checks that on the machine at hand before it is used."""
    n = z.shape[1]
    for i in range(q + 1):  # the sums run over j; k innermost, so the loop vectorises
        for k in range(n):
            out[i, k] = 0.0
        for j in range(q + 1):
            p = pascal[i, j]
            for k in range(n):
                out[i, k] = _fma(p, z[j, k], out[i, k])
    for k in range(n):
        yp_out[k] = out[1, k] / h


@numba.njit(cache=True, nogil=True)
def correct(z_pred, lvec, delta, q, z):
    """z[:q+1] = z_pred[:q+1] + l[:, None] * delta (the accepted Nordsieck array)."""
    for j in range(q + 1):
        lj = lvec[j]
        for k in range(delta.size):
            z[j, k] = z_pred[j, k] + lj * delta[k]


@numba.njit(cache=True, nogil=True)
def newton_update(x, scale, y, yp, cj, w, y_new, yp_new, dw):
    """Fill y_new, yp_new and dw from the solve x = J^-1 F (formulas above); return
    dw . dw (BLAS's ddot, as numpy's ``dw.dot(dw)``)."""
    for i in range(x.size):
        d = -x[i]
        if scale != 1.0:
            d = d * scale
        y_new[i] = y[i] + d
        yp_new[i] = yp[i] + cj * d
        dw[i] = d * w[i]
    return np.dot(dw, dw)


@numba.njit(cache=True, nogil=True)
def wrms(v, w):
    """sqrt(mean((v_i w_i)^2)), the dot product by BLAS's ddot as numpy's."""
    vw = np.empty(v.size)
    for i in range(v.size):
        vw[i] = v[i] * w[i]
    return math.sqrt(np.dot(vw, vw) / v.size)


@numba.njit(cache=True, nogil=True)
def lu_solve_small(lu, piv, b):
    """b <- A^-1 b in place from LAPACK's getrf factors (lu, piv 0-based), as
    LAPACK's getrs with one right-hand side: the row interchanges, then L (unit
    diagonal) and U column by column (b_k -= b_i L_ki; b_i /= U_ii, b_k -= b_i U_ki).

    OpenBLAS does these column updates with its axpy kernel, whose vector part
    (16 elements and more at a time) fuses multiply and add: below that, as here,
    every product and difference is rounded on its own, so for n <= SMALL_DENSE
    the result is getrs's to the bit (``dense_solve_matches_lapack`` checks that on
    the machine at hand before it is used)."""
    n = b.size
    for i in range(n):
        p = piv[i]
        if p != i:
            t = b[i]
            b[i] = b[p]
            b[p] = t
    for i in range(n):
        bi = b[i]
        for k in range(i + 1, n):
            b[k] -= bi * lu[k, i]
    for i in range(n - 1, -1, -1):
        b[i] = b[i] / lu[i, i]
        bi = b[i]
        for k in range(i):
            b[k] -= bi * lu[k, i]


@numba.njit(cache=True, nogil=True)
def newton_update_lu(lu, piv, f, scale, y, yp, cj, w, y_new, yp_new, dw):
    """``newton_update`` with the solve x = J^-1 F (``lu_solve_small``) in the loop."""
    x = f.copy()
    lu_solve_small(lu, piv, x)
    return newton_update(x, scale, y, yp, cj, w, y_new, yp_new, dw)


@numba.njit(cache=True, nogil=True)
def rescale(z, q, ratio):
    """Row j of z times ratio**j (j = 1..q), the factor formed as ratio * ratio * ...
    one multiplication after the other as in ``nordsieck.rescale``."""
    factor = 1.0
    for j in range(1, q + 1):
        factor *= ratio
        for k in range(z.shape[1]):
            z[j, k] *= factor


@numba.njit(cache=True, nogil=True)
def weights(y, rtol, atol, out):
    """out = 1 / (rtol |y| + atol), atol an array of y's size. Returns nothing: a
    returned array is boxed anew by numba, 0.3 to 1 us a call (measured)."""
    for i in range(y.size):
        out[i] = 1.0 / (rtol * abs(y[i]) + atol[i])


@numba.njit(cache=True, nogil=True)
def delta_wrms(y, y_pred, w, delta):
    """delta = y - y_pred (Milne's Delta) and wrms(delta, w) in one call, each
    formed as numpy forms them (the difference rounded, then the product, then
    BLAS's ddot)."""
    n = y.size
    vw = np.empty(n)
    for i in range(n):
        delta[i] = y[i] - y_pred[i]
        vw[i] = delta[i] * w[i]
    return math.sqrt(np.dot(vw, vw) / n)


@numba.njit(cache=True, nogil=True)
def wrms_order_errors(zq, delta, delta_prev, w):
    """(wrms(z_q, w), wrms(delta - delta_prev, w)) in one call: the two norms of the
    order choice (``bdf.NordsieckBDF._choose_next``), each formed as numpy forms it
    (the difference rounded, then the product, then BLAS's ddot)."""
    n = zq.size
    a = np.empty(n)
    b = np.empty(n)
    for i in range(n):
        a[i] = zq[i] * w[i]
        b[i] = (delta[i] - delta_prev[i]) * w[i]
    return math.sqrt(np.dot(a, a) / n), math.sqrt(np.dot(b, b) / n)


#: largest n of a dense matrix whose solve runs compiled (``lu_solve_small``)
SMALL_DENSE = 15
_PREDICT_OK = None
_SOLVE_OK = None
_DOT_OK = None


def dot_matches_numpy() -> bool:
    """numba's np.dot (scipy's BLAS) gives numpy's ``a.dot(a)`` bit for bit (checked
    once per process on random vectors of several sizes; otherwise the step keeps
    numpy's dot products)."""
    global _DOT_OK
    if _DOT_OK is None:
        rng = np.random.default_rng(777)
        ok = True
        for n in (1, 2, 3, 7, 8, 15, 16, 17, 33, 100, 1001, 7015):
            v = rng.standard_normal(n) * 10.0 ** rng.uniform(-5, 5, n)
            w = 10.0 ** rng.uniform(-5, 5, n)
            vw = v * w
            ok = ok and wrms(v, w) == math.sqrt(vw.dot(vw) / vw.size)
            d = rng.standard_normal(n)
            dw, y1, y2 = np.empty(n), np.empty(n), np.empty(n)
            ss = newton_update(d, 0.7, v, v, 3.0, w, y1, y2, dw)
            ok = ok and ss == dw.dot(dw)
            delta = np.empty(n)
            ok = ok and delta_wrms(v, d, w, delta) == wrms(v - d, w)
            ok = ok and np.array_equal(delta, v - d)
            e_down, e_up = wrms_order_errors(v, d, w, w)
            vw, dd = v * w, (d - w) * w
            ok = ok and e_down == math.sqrt(vw.dot(vw) / n)
            ok = ok and e_up == math.sqrt(dd.dot(dd) / n)
        _DOT_OK = bool(ok)
    return _DOT_OK


def dense_solve_matches_lapack() -> bool:
    """``lu_solve_small`` gives scipy's LAPACK getrs bit for bit on random systems of
    every n up to SMALL_DENSE (checked once per process; otherwise the step keeps
    LAPACK's solve)."""
    global _SOLVE_OK
    if _SOLVE_OK is None:
        import scipy.linalg

        (getrs,) = scipy.linalg.get_lapack_funcs(("getrs",), (np.zeros(1),))
        rng = np.random.default_rng(54321)
        ok = True
        for n in range(1, SMALL_DENSE + 1):
            for _ in range(4):
                a = rng.standard_normal((n, n)) * 10.0 ** rng.uniform(-3, 3, (n, n))
                lu, piv = scipy.linalg.lu_factor(a + np.eye(n), check_finite=False)
                b = rng.standard_normal(n) * 10.0 ** rng.uniform(-8, 8, n)
                x = b.copy()
                lu_solve_small(lu, piv, x)
                ok = ok and np.array_equal(x, getrs(lu, piv, b)[0])
        _SOLVE_OK = bool(ok)
    return _SOLVE_OK


def predict_matches_numpy() -> bool:
    """``predict`` gives numpy's ``P @ z`` bit for bit on random arrays of every order
    (checked once per process: the sums follow the BLAS kernel, which depends on the
    machine; where they differ the step keeps numpy's product)."""
    global _PREDICT_OK
    if _PREDICT_OK is None:
        from dnasim.solver import nordsieck as nd

        rng = np.random.default_rng(12345)
        ok = True
        for n in (3, 8, 37):
            z = rng.standard_normal((nd.MAX_ORDER + 2, n)) * 10.0 ** rng.uniform(-8, 8, (1, n))
            for q in range(1, nd.MAX_ORDER + 1):
                out, yp = np.empty_like(z), np.empty(n)
                predict(nd.pascal_matrix(q), z, q, 0.37, out, yp)
                ref = nd.pascal_matrix(q) @ z[: q + 1]
                ok = ok and np.array_equal(out[: q + 1], ref) and np.array_equal(yp, ref[1] / 0.37)
        _PREDICT_OK = bool(ok)
    return _PREDICT_OK
