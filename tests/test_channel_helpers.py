"""The channel's fast helpers against the formulas they replace: the compiled LMTD of
long channels (dnasim.model.lmtd_numba) against the numpy ``physics.lmtd`` (used
below ``LMTD_NUMBA_MIN`` elements), and ``physics.upwind_weight_pair`` against two
calls of ``upwind_weight``.

The reference is the numpy formula (softplus of +-dT and the logarithmic mean, itself
checked against the closed-form LMTD in tests/test_walls.py and the plant tests): the
compiled loop makes the same operations, so the two agree to round-off. Why not
bit-for-bit: numpy's vectorised ``np.log`` and the C library's ``log`` differ in the
last bit for about 1 argument in 10^4, and the logarithmic mean (x - y)/ln(x/y) for
|x - y|/(x + y) just above 1e-3 divides by a logarithm of about 2e-3, so one ulp of
it is ~1e-13 relative: rtol 1e-12. Where +dT and -dT give nearly equal softplus
values (|dT| << dT_reg) the signed difference of two terms of about 0.7 dT_reg loses
the leading digits, so the round-off is absolute, a few 1e-16 dT_reg: atol 1e-14 dT_reg.
"""

from __future__ import annotations

import numpy as np
import pytest

from dnasim.model import physics

numba_lmtd = pytest.importorskip("dnasim.model.lmtd_numba")


@pytest.mark.parametrize("scale", [0.1, 3.0, 50.0, 500.0, 1e5])
@pytest.mark.parametrize("dT_reg", [1.0, 0.05])
def test_compiled_lmtd_equals_numpy_to_round_off(monkeypatch, scale, dT_reg):
    rng = np.random.default_rng(7)
    a = rng.standard_normal(20000) * scale
    b = rng.standard_normal(20000) * scale
    a[::7] = b[::7]  # equal ends: the series branch
    a[::11] = 0.0  # softplus at exactly zero
    b[::13] = 1e-300
    a[5] = np.nan  # NaN stays NaN
    monkeypatch.setattr(physics, "LMTD_NUMBA_MIN", 10**9)  # numpy for the reference
    with np.errstate(invalid="ignore"):  # the NaN element
        ref = physics.lmtd(a, b, dT_reg)
    new = numba_lmtd.lmtd(a, b, dT_reg)
    assert np.array_equal(np.isnan(ref), np.isnan(new))
    ok = ~np.isnan(ref)
    np.testing.assert_allclose(new[ok], ref[ok], rtol=1e-12, atol=1e-14 * dT_reg)


def test_long_arrays_use_the_compiled_loop(monkeypatch):
    """physics.lmtd hands arrays of LMTD_NUMBA_MIN or more to the compiled loop."""
    calls = []
    monkeypatch.setattr(physics, "_lmtd_compiled", lambda: lambda *a: calls.append(a) or 0.0)
    n = physics.LMTD_NUMBA_MIN
    physics.lmtd(np.ones(n), np.ones(n), 1.0)
    assert len(calls) == 1
    physics.lmtd(np.ones(n - 1), np.ones(n - 1), 1.0)  # numpy below the threshold
    assert len(calls) == 1


def test_upwind_weight_pair_is_two_calls_bit_for_bit():
    """(w(m), w(-m)) from one pass: q and the tail are even in m and (-m) + q == q - m
    in IEEE arithmetic, so the pair equals the two calls exactly, inside and outside the
    regularisation band and at m = 0."""
    rng = np.random.default_rng(5)
    m = np.concatenate([rng.standard_normal(2000) * s for s in (1e-6, 1e-3, 1e-2, 1.0, 100.0)])
    m[::17] = 0.0
    for eps in (1e-3, 2e-2, 0.7):
        wp, wm = physics.upwind_weight_pair(m, eps)
        np.testing.assert_array_equal(wp, physics.upwind_weight(m, eps))
        np.testing.assert_array_equal(wm, physics.upwind_weight(-m, eps))


def test_upwind_weight_of_an_array_is_the_scalar_formula_bit_for_bit():
    """The array path (which skips the band polynomial when every flow is outside the
    band) gives each element the number of the scalar path (Python floats, the same
    operations), for arrays all outside the band, all inside, and mixed."""
    rng = np.random.default_rng(9)
    eps = 2e-2
    for scale in (1e-3, 1e-2, 1.0, 50.0):  # inside, mixed, outside, far outside
        m = rng.standard_normal(40) * scale
        m[::11] = 0.0 if scale < 1.0 else m[::11]
        w = physics.upwind_weight(m, eps)
        assert list(w) == [physics.upwind_weight(float(v), eps) for v in m]
        wp, wm = physics.upwind_weight_pair(m, eps)
        assert list(wp) == list(w) and list(wm) == list(physics.upwind_weight(-m, eps))
