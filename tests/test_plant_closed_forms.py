"""Plant model against closed-form solutions (ideal gas with constant cp).

Air is the media helper's ideal gas: h = cp (T - T_ref) with constant cp, so
m (h_in - h_out) = m cp (T_in - T_out) exactly and the pipe's heat balance has
textbook solutions.
"""

import math

import numpy as np
import pytest

from dnasim.library import MassFlowBoundary, Pipe, PressureBoundary, Valve
from dnasim.media import get_medium
from dnasim.plant.plant import Plant
from dnasim.start.initial import initial_values

CP = get_medium("Air").state(1e5, 3e5).cp


def fixed_wall_pipe(n, heat_transfer, kA=150.0, T_in=600.0, T_wall=300.0):
    plant = Plant("fixed_wall", medium="Air")
    plant.add(PressureBoundary("src", p=2e5, T=T_in, m_nominal=0.1))
    plant.add(
        Pipe(
            "pipe",
            V=0.08,
            kA=kA,
            k=1.2e5,
            T_wall=T_wall,
            n_volumes=n,
            heat_transfer=heat_transfer,
            m_nominal=0.1,
        )
    )
    plant.add(Valve("valve", C=3.2e-4, opening=1.0, m_nominal=0.1))
    plant.add(PressureBoundary("sink", p=1e5, m_nominal=0.1))
    for a, b in [
        ("src.port", "in"),
        ("pipe.inlet", "in"),
        ("pipe.outlet", "out"),
        ("valve.inlet", "out"),
        ("valve.outlet", "exit"),
        ("sink.port", "exit"),
    ]:
        plant.connect(a, b)
    return plant


def steady_outlet(plant):
    dae = plant.compile()
    y, _ = initial_values(dae, 0.0, "steady")
    row = dict(zip(dae.output_names(), dae.output_row(0.0, y, np.zeros_like(y)), strict=False))
    return row["pipe.T_out"], row["pipe.m[0]"]


@pytest.mark.parametrize("n", [1, 4, 20])
def test_lmtd_pipe_matches_exponential_for_any_n(n):
    # With the log-mean temperature difference each volume's steady balance
    # m cp (T_a - T_b) = kA_i (T_a - T_b)/ln((T_a-T_w)/(T_b-T_w)) is solved exactly by
    # T_b - T_w = (T_a - T_w) exp(-kA_i/(m cp)), so there is no discretisation error:
    # only the Newton tolerance (1e-10 relative steps) remains -> 1e-7 K.
    T_w, T_in, kA = 300.0, 600.0, 150.0
    T_out, m = steady_outlet(fixed_wall_pipe(n, "lmtd", kA, T_in, T_w))
    exact = T_w + (T_in - T_w) * math.exp(-kA / (m * CP))
    assert abs(T_out - exact) < 1e-7


def test_discretisation_error_falls_with_n():
    # Upwind ("outlet") and arithmetic-mean ("mean") temperature differences are
    # the usual finite-volume discretisations; per volume (a = NTU/n):
    #   outlet: theta_i = theta_{i-1}/(1 + a)                -> error O(1/n)
    #   mean:   theta_i = theta_{i-1}(1 - a/2)/(1 + a/2)     -> error O(1/n^2)
    # The computed outlet temperature must equal these products (to Newton
    # tolerance, 1e-7 K) and the error against exp(-NTU) must fall with n at the
    # known rate.
    T_w, T_in, kA = 300.0, 600.0, 150.0
    errors = {"outlet": [], "mean": []}
    ns = [4, 16, 64]
    for scheme in errors:
        for n in ns:
            T_out, m = steady_outlet(fixed_wall_pipe(n, scheme, kA, T_in, T_w))
            ntu = kA / (m * CP)
            a = ntu / n
            factor = (1 + a) ** -n if scheme == "outlet" else ((1 - a / 2) / (1 + a / 2)) ** n
            assert abs(T_out - (T_w + (T_in - T_w) * factor)) < 1e-7
            errors[scheme].append(abs(T_out - (T_w + (T_in - T_w) * math.exp(-ntu))))
    # first order: quadrupling n divides the error by ~4 (3.5 .. 4.5 allows the
    # higher-order terms: 3.71 and 3.92 in exact arithmetic at NTU = 1.5);
    # second order: by ~16 (13 .. 17; exact 16.19 and 16.01).
    for e1, e2 in zip(errors["outlet"], errors["outlet"][1:], strict=False):
        assert 3.5 < e1 / e2 < 4.5
    for e1, e2 in zip(errors["mean"], errors["mean"][1:], strict=False):
        assert 13.0 < e1 / e2 < 17.0


def test_lumped_wall_first_order_response():
    # A constant air flow m at T_in heats a wall of capacity C from T_w0. With the
    # fluid's own heat capacity negligible (V = 1 litre of air: ~1 J/K against
    # C = 1e4 J/K), the fluid is quasi-steady: Q = m cp (1 - exp(-NTU)) (T_in - T_w),
    # so T_w(t) = T_in - (T_in - T_w0) exp(-t/tau), tau = C / (m cp (1 - exp(-NTU))).
    m, T_in, T0, kA, C = 0.1, 400.0, 300.0, 100.0, 1.0e4
    plant = Plant("wall", medium="Air")
    plant.add(MassFlowBoundary("src", m=m, T=T_in, m_nominal=m))
    plant.add(
        Pipe("pipe", V=1e-3, kA=kA, k=1e5, C_wall=C, m_nominal=m, p0=1.05e5, T0=T0, T_wall0=T0)
    )
    plant.add(Valve("valve", C=m / math.sqrt(5e3), opening=1.0, m_nominal=m))
    plant.add(PressureBoundary("sink", p=1e5, m_nominal=m))
    for a, b in [
        ("src.port", "in"),
        ("pipe.inlet", "in"),
        ("pipe.outlet", "out"),
        ("valve.inlet", "out"),
        ("valve.outlet", "exit"),
        ("sink.port", "exit"),
    ]:
        plant.connect(a, b)
    tau = C / (m * CP * (1 - math.exp(-kA / (m * CP))))
    t_eval = np.linspace(0, 3 * tau, 31)
    res = plant.simulate(3 * tau, start="given", rtol=1e-7, atol_scaled=1e-8, t_eval=t_eval)
    assert res.success
    exact = T_in - (T_in - T0) * np.exp(-res.t / tau)
    # Model error from the neglected fluid capacity: relative ~ M cv / C ~ 1e-4 of
    # the 100 K span (0.01 K); plus the integration error (rtol 1e-7). 0.03 K.
    assert np.max(np.abs(res["pipe.T_w[0]"] - exact)) < 0.03
    # and the wall really moved most of the way
    assert res["pipe.T_w[0]"][-1] > T_in - 0.06 * (T_in - T0)
