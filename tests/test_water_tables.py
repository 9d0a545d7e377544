"""Bicubic IF97 tables (dnasim.media.if97_tables): the stated error bound against the
IF97 kernel, continuity across the saturation line, the IF97 answer where the tables
do not answer, and selection by name."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("numba")

from dnasim.media import get_medium  # noqa: E402
from dnasim.media import if97_numba as NB  # noqa: E402
from dnasim.media import if97_tables as TW  # noqa: E402


@pytest.fixture(scope="module")
def water():
    return get_medium("Water", backend="IF97-TABLES")


def random_states(n, seed=7):
    """States spread over the tables' domain: ln p uniform in [700 Pa, 100 MPa], h
    uniform between h(p, 273.2 K) and h(p, 1073 K) (liquid, dome, vapour, region 3)."""
    rng = np.random.default_rng(seed)
    p = np.exp(rng.uniform(np.log(700.0), np.log(100e6), n))
    ha = np.array([NB.h_pT_scalar(x, 273.2)[0] for x in p])
    hb = np.array([NB.h_pT_scalar(x, 1073.0)[0] for x in p])
    return p, ha + rng.uniform(0.0, 1.0, n) * (hb - ha)


def test_error_bound_against_if97(water):
    p, h = random_states(50000)
    r = water.states(p, h)
    ref = NB.ph_arrays(p, h)
    # the bounds stated in the module (RHO_REL_BOUND 3e-5, T_ABS_BOUND 10 mK): measured
    # maxima are 2e-5 and 5 mK, so a change that loosens the tables fails here
    assert np.max(np.abs(r.rho / ref.rho - 1.0)) < TW.RHO_REL_BOUND
    assert np.max(np.abs(r.T - ref.T)) < TW.T_ABS_BOUND
    # u = h - p/rho from the tabulated rho: the same relative bound times p v / u
    np.testing.assert_allclose(r.u, h - p / r.rho, rtol=1e-13, atol=1e-9)
    # every region is sampled (else the test would not cover the dome or region 3)
    assert set(np.unique(ref.region)) >= {1, 2, 3, 4}
    # the dome's quality: x = (h - h')/(h'' - h') with spline h', h'' (2e-7 relative)
    dome = ref.region == 4
    assert np.max(np.abs(r.x[dome] - ref.x[dome])) < 1e-4


def test_band_and_outside_are_if97(water):
    # inside the near-critical band and in region 5 the IF97 kernel answers: identical
    p = np.array([21e6, 22.064e6, 25e6, 1e6])
    h = np.array([1.8e6, 2.1e6, 2.2e6, 4.8e6])  # the last: 1e6 Pa, about 1300 K
    r = water.states(p, h)
    ref = NB.ph_arrays(p, h)
    np.testing.assert_array_equal(r.rho, ref.rho)
    np.testing.assert_array_equal(r.T, ref.T)
    # the scalar path likewise
    assert water.state(21e6, 1.8e6).rho == get_medium("Water").state(21e6, 1.8e6).rho


@pytest.mark.parametrize("p", [1e4, 1e5, 1e6, 5e6, 15e6, 19.5e6])
def test_continuous_across_the_saturation_line(water, p):
    # h' and h'' of the tables' own splines: one ulp either side, T and rho must agree
    # to round-off of the spline evaluation (1e-9), not to the error bound
    hl, hv = water.saturation_enthalpies(np.array([p]))
    for hs in (float(hl[0]), float(hv[0])):
        a = water.states(np.array([p, p]), np.array([hs * (1 - 1e-12), hs * (1 + 1e-12)]))
        assert abs(a.rho[1] / a.rho[0] - 1.0) < 1e-6  # IF97's h' vs the spline's: 2e-7
        assert abs(a.T[1] - a.T[0]) < 1e-4


def test_state_T_rho_u_and_plant_name(water):
    from dnasim.media.if97_tables import TabulatedWater

    assert isinstance(get_medium("IF97-TABLES::Water"), TabulatedWater)
    assert get_medium("if97-tables::water") is water
    st = water.state(5e6, 3.2e6)
    T, rho, u = water.T_rho_u(np.array([5e6]), np.array([3.2e6]))
    assert (T[0], rho[0], u[0]) == (st.T, st.rho, st.u)
    ref = get_medium("Water").state(5e6, 3.2e6)
    assert st.rho == pytest.approx(ref.rho, rel=TW.RHO_REL_BOUND)  # the stated bound
    # (d rho/d h)_p of the spline against a central difference of IF97 (1e-3: the
    # derivative of an interpolant, measured 2e-4 here)
    d = 10.0
    fd = (
        get_medium("Water").state(5e6, 3.2e6 + d).rho
        - get_medium("Water").state(5e6, 3.2e6 - d).rho
    ) / (2 * d)
    assert st.drho_dh_p == pytest.approx(fd, rel=1e-3)


def test_out_of_range_raises(water):
    from dnasim.media import PropertyError

    with pytest.raises(PropertyError, match="Water"):
        water.state(200e6, 1e6)


def test_tables_file_is_reused(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    path = TW.table_path()
    assert path.parent == tmp_path and not path.exists()
    t1 = TW.load_tables()
    assert path.is_file()
    t2 = TW.load_tables()
    assert set(t1) == set(t2) and all(np.array_equal(t1[k], t2[k]) for k in t1)


def test_memo_computes_moved_points_only_and_gives_the_same_numbers(water):
    p, h = random_states(200, seed=11)
    memo = water.states_memo()
    ref = water.T_rho_u(p, h)  # without memo
    a = water.T_rho_u(p, h, None, memo)
    assert memo.computed == p.size + int(np.sum((p >= TW.P_BAND[0]) & (p <= TW.P_BAND[1])))
    h2 = h.copy()
    h2[[3, 50]] *= 1.001
    b = water.T_rho_u(p, h2, None, memo)
    # two points moved, and the points in the near-critical band go to IF97 each call
    band = int(np.sum((p >= TW.P_BAND[0]) & (p <= TW.P_BAND[1])))
    assert memo.computed == 2 + band
    c = water.T_rho_u(p, h, None, memo)
    for x, y in zip(ref, a, strict=True):
        np.testing.assert_array_equal(x, y)
    for x, y in zip(ref, c, strict=True):
        np.testing.assert_array_equal(x, y)
    assert b[1][3] != a[1][3] and b[1][4] == a[1][4]
