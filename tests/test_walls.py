"""Walls (dnasim.library.submodels.walls on Pipe): steady conduction through layers and
an outer convection against the closed-form resistances, the exponential
response of a lumped wall to an outer temperature step, a heat flux input, and
the balances over a run."""

import math

import numpy as np
import pytest
from plant_checks import balances

from dnasim.core.timefunctions import Ramp, Step
from dnasim.library import MassFlowBoundary, Pipe, PressureBoundary, Valve
from dnasim.plant.plant import Plant

R_IN, R_OUT, LENGTH, LAMBDA = 0.05, 0.08, 10.0, 15.0  # m, m, m, W/(m K)
KA = 5000.0  # W/K fluid to the inner surface
M = 1.0  # kg/s


def water_line(**pipe):
    """Hot water (20 bar, 450 K, 1 kg/s) through one pipe volume, a valve, a sink."""
    p = Plant("wall", medium="Water")
    p.add(MassFlowBoundary("src", m=M, T=450.0, m_nominal=M))
    kw = dict(V=0.1, k=1e4, kA=KA, C_wall=2e5, heat_transfer="outlet", m_nominal=M)
    kw.update(pipe)
    p.add(Pipe("pipe", **kw))
    p.add(Valve("v", C=1e-3, opening=1.0, m_nominal=M))
    p.add(PressureBoundary("sink", p=20e5, m_nominal=M))
    for a, n in [
        ("src.port", "a"),
        ("pipe.inlet", "a"),
        ("pipe.outlet", "b"),
        ("v.inlet", "b"),
        ("v.outlet", "c"),
        ("sink.port", "c"),
    ]:
        p.connect(a, n)
    return p


def R_shell():
    return math.log(R_OUT / R_IN) / (2 * math.pi * LAMBDA * LENGTH)


@pytest.mark.parametrize("layers", [1, 4])
def test_steady_conduction_through_layers(layers):
    res = water_line(
        wall_layers=layers,
        r_in=R_IN,
        r_out=R_OUT,
        length=LENGTH,
        wall_conductivity=LAMBDA,
        T_outer=300.0,
    ).simulate(10.0, start="steady", rtol=1e-8)
    assert res.success, res.message
    Q, T_f = res["pipe.Q_total"][-1], res["pipe.T_out"][-1]
    # fluid -> inner surface (1/kA) -> shell ln(r2/r1)/(2 pi lambda L) -> outer surface
    # at 300 K; the node conductances are exact for steady conduction, so any number
    # of layers gives the closed form to the steady solve's tolerance (1e-8)
    assert Q == pytest.approx((T_f - 300.0) / (1 / KA + R_shell()), rel=1e-8)
    # the heat leaves through the outer surface: Q_passed grows at Q
    assert np.diff(res["pipe.Q_passed"])[-1] / np.diff(res.t)[-1] == pytest.approx(Q, rel=1e-6)
    assert Q > 1e4  # a real heat flow: the test can fail


def test_steady_conduction_with_outer_convection():
    kA_out = 800.0
    res = water_line(
        wall_layers=3,
        r_in=R_IN,
        r_out=R_OUT,
        length=LENGTH,
        wall_conductivity=LAMBDA,
        T_outer=290.0,
        kA_outer=kA_out,
    ).simulate(10.0, start="steady", rtol=1e-8)
    assert res.success, res.message
    Q, T_f = res["pipe.Q_total"][-1], res["pipe.T_out"][-1]
    # three resistances in series, closed form (1e-8: steady solve tolerance)
    assert Q == pytest.approx((T_f - 290.0) / (1 / KA + R_shell() + 1 / kA_out), rel=1e-8)
    # the fluid's energy balance: m (h_in - h_out) = Q
    h_in, h_out = res["a.h"][-1], res["b.h"][-1]
    assert M * (h_in - h_out) == pytest.approx(Q, rel=1e-8)


def test_lumped_wall_exponential_response_to_an_outer_step():
    C, kA_out = 2e5, 400.0  # J/K, W/K: time constant 500 s
    step = Step(10.0, 300.0, 400.0)
    res = water_line(kA=0.0, C_wall=C, T_outer=step, kA_outer=kA_out, T_wall0=300.0).simulate(
        1500.0, start="given", rtol=1e-8, atol_scaled=1e-10
    )
    assert res.success, res.message
    t, T = res.t, res["pipe.T_w[0]"]
    after = t > 10.0
    exact = 400.0 - 100.0 * np.exp(-(t[after] - 10.0) * kA_out / C)
    # C dT/dt = kA_out (T_outer - T): exponential with tau = C/kA_out = 500 s;
    # 1e-4 K: the BDF's global error at rtol 1e-8 on a 100 K step
    assert np.max(np.abs(T[after] - exact)) < 1e-4
    assert np.all(np.abs(T[t <= 10.0] - 300.0) < 1e-9)
    assert T[-1] > 390.0  # three time constants: the step has mostly arrived


def test_heat_flux_input_heats_the_fluid_and_balances_close():
    Q_in = Ramp(10.0, 110.0, 0.0, 2e5)  # W
    p = water_line(Q_outer=Q_in, C_wall=2e5, kA=KA)
    res = p.simulate(3000.0, start="given", rtol=1e-7)
    assert res.success, res.message
    # late in the run the wall has settled: the fluid takes the whole flux,
    # m (h_out - h_in) = Q_outer (5e-4: what is left of the wall's transient after
    # 2900 s with tau = C/kA ~ 40 s and the fluid volume's)
    h_in, h_out = res["a.h"][-1], res["b.h"][-1]
    assert M * (h_out - h_in) == pytest.approx(2e5, rel=5e-4)
    assert res["pipe.Q_total"][-1] == pytest.approx(-2e5, rel=5e-4)
    # balances: stored fluid + wall energy against the boundaries and Q_passed
    # (bound 1e-6 of the throughput, the issue's)
    err_M, thr_M, err_E, thr_E = balances(p, res)
    assert err_M < 1e-6 * thr_M and err_E < 1e-6 * thr_E, (err_M / thr_M, err_E / thr_E)
    assert res["pipe.Q_passed"][-1] < -2e5 * 2000  # the heat came in from outside
