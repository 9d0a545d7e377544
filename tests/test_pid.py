"""PIDController against closed forms on a first-order plant G(s) = K/(T s + 1)
(a FirstOrderLag block): the closed-loop step response with a PI (pole-zero
cancellation) and a filtered PID (the linear closed loop, by scipy's exact
matrix-exponential step response), back-calculation anti-windup (the integral's
closed form while saturated, the recovery time), bumpless transfer and per-unit
gains."""

import math

import numpy as np
import pytest
import scipy.signal

from dnasim.core.errors import PlantError
from dnasim.core.timefunctions import Step, TimeFunction
from dnasim.library.pid import PIDController
from dnasim.library.signal_blocks import FirstOrderLag
from dnasim.plant.plant import Plant

K, T = 2.0, 10.0  # plant gain [1], time constant [s]
RTOL, ATOL = 1e-9, 1e-11
# global error of the BDF run at rtol 1e-9 on these smooth linear loops: a few
# hundred times the local tolerance in the worst case; 1e-6 of the unit step
# leaves that margin and is still far below any modelling error (a wrong D-part
# sign or filter constant changes the response by 1e-2 or more)
TOL = 1e-6


def loop(setpoint, **pid):
    plant = Plant("loop")
    plant.add(FirstOrderLag("G", T=T, k=K))
    kw = dict(z_min=-1e3, z_max=1e3, error_sign="setpoint-measured", measured_nominal=1.0)
    kw.update(pid)
    plant.add(PIDController("pid", setpoint=setpoint, **kw))
    plant.link("pid.z", "G.u")
    plant.link("G.y", "pid.measured")
    return plant


def run(plant, t_end, **kw):
    res = plant.simulate(t_end, start="steady", rtol=RTOL, atol_scaled=ATOL, **kw)
    assert res.success, res.message
    return res


def test_pi_step_is_first_order_with_pole_zero_cancellation():
    # T_i = T cancels the plant pole: y/w = 1/(1 + s T_i/(Kp K))
    Kp = 1.5
    res = run(loop(Step(1.0, 0.0, 1.0), Kp=Kp, T_i=T), 30.0)
    t, y = res.t, res["G.y"]
    tau = T / (Kp * K)
    exact = np.where(t >= 1.0, 1.0 - np.exp(-np.clip(t - 1.0, 0.0, None) / tau), 0.0)
    after = t > 1.0
    assert np.max(np.abs(y[after] - exact[after])) < TOL
    assert np.all(np.abs(y[t < 1.0]) < TOL)


def _closed_loop(Kp, T_i, T_d, N):
    """y/w of the loop with the D part on the measurement (c_d = 0)."""
    nG, dG = np.array([K]), np.array([T, 1.0])
    nPI, dPI = np.array([Kp * T_i, Kp]), np.array([T_i, 0.0])
    if T_d > 0:
        nD, dD = np.array([Kp * T_d, 0.0]), np.array([T_d / N, 1.0])
    else:
        nD, dD = np.array([0.0]), np.array([1.0])
    num = np.polymul(np.polymul(nG, nPI), dD)
    den = np.polyadd(
        np.polymul(np.polymul(dG, dPI), dD),
        np.polymul(nG, np.polyadd(np.polymul(nPI, dD), np.polymul(nD, dPI))),
    )
    return scipy.signal.lti(num, den)


def _step_response(sys, t):
    """Unit-step response of an LTI system in closed form: with x' = A x + B u,
    y = C x + D u, x(0) = 0, u = 1: y(t) = C A^-1 (e^{A t} - I) B + D."""
    import scipy.linalg

    A, B, C, D = scipy.signal.tf2ss(sys.num, sys.den)
    n = A.shape[0]
    out = np.empty(t.size)
    for k, tk in enumerate(t):
        x = np.linalg.solve(A, (scipy.linalg.expm(A * tk) - np.eye(n)) @ B)
        out[k] = (C @ x + D)[0, 0]
    return out


@pytest.mark.parametrize("T_d", [0.0, 2.0])
def test_pid_step_against_the_linear_closed_loop(T_d):
    Kp, T_i, N = 2.0, 6.0, 8.0
    res = run(loop(Step(1.0, 0.0, 1.0), Kp=Kp, T_i=T_i, T_d=T_d, N=N), 40.0)
    t, y = res.t, res["G.y"]
    after = t > 1.0
    tt = t[after] - 1.0
    sys = _closed_loop(Kp, T_i, T_d, N)
    y_exact = _step_response(sys, tt)
    assert np.max(np.abs(y[after] - y_exact)) < TOL
    if T_d > 0:
        # no derivative kick: the D part acts on the measurement, which is continuous
        k = int(np.flatnonzero(t == 1.0)[0])  # the row after the time event
        assert abs(res["pid.m_D"][k]) < TOL


def test_d_part_with_setpoint_weight_kicks_by_kp_n():
    # c_d = 1: a step of w by 1 makes m_D jump by -Kp N (e_D = w - y jumps by 1,
    # the filter state x_f cannot jump): m_D = Kp N (e_D - x_f)
    Kp, N = 2.0, 8.0
    res = run(loop(Step(1.0, 0.0, 1.0), Kp=Kp, T_i=6.0, T_d=2.0, N=N, c_d=1.0), 1.5, max_step=0.01)
    # the output row at a time event holds the values after it; the row before
    # is the last step before the event
    k = int(np.flatnonzero(res.t == 1.0)[0])
    assert res["pid.m_D"][k - 1] == 0.0
    assert res["pid.m_D"][k] == pytest.approx(Kp * N, rel=1e-9)


class _Steps(TimeFunction):
    """0 before 1 s, 3 from 1 s to 40 s, 1 from 40 s on."""

    breakpoints = (1.0, 40.0)

    def __call__(self, t):
        return 0.0 if t < 1.0 else 3.0 if t < 40.0 else 1.0


def _saturating(anti_windup):
    # the set point 3 is out of reach (K z_max = 2) from t = 1 s to 40 s, then 1
    w = _Steps()
    plant = loop(w, Kp=0.8, T_i=5.0, z_min=0.0, z_max=1.0, anti_windup=anti_windup)
    return run(plant, 200.0)


def _leave_time(res):
    return [e["t"] for e in res.events if e["name"] == "pid.upper"]


def test_back_calculation_bounds_the_integral_while_saturated():
    res = _saturating(True)
    enter, leave = _leave_time(res)[:2]
    assert enter == 1.0  # the set-point step carries v over z_max at the time event
    sat = (res.t > enter) & (res.t < leave)
    # with T_t = T_i the back-calculation gives dm_I/dt = (z_max - m_I)/T_i in
    # saturation (Kp e/T_i + (z_max - Kp e - m_I)/T_t): m_I -> z_max, never above
    t0 = res.t[sat][0]
    m0 = res["pid.m_I"][sat][0]
    exact = 1.0 + (m0 - 1.0) * np.exp(-(res.t[sat] - t0) / 5.0)
    assert np.max(np.abs(res["pid.m_I"][sat] - exact)) < TOL
    assert res["pid.m_I"].max() <= 1.0 + TOL
    # recovery: at the set-point step down v = Kp (1 - y) + m_I < z_max at once,
    # so the output leaves the limit at the time event itself
    assert leave == 40.0


def test_without_anti_windup_the_integral_winds_up_and_recovers_late():
    res = _saturating(False)
    enter, leave = _leave_time(res)[:2]
    sat = (res.t > enter) & (res.t < leave)
    # in saturation u = z_max = 1: y = K (1 - exp(-(t - 1)/T)) from y(1) = 0 and
    # m_I = m_I(1) + Kp/T_i int (3 - y) dt, a closed form
    t = res.t[sat]
    y = K * (1.0 - np.exp(-(t - 1.0) / T))
    integral = 3.0 * (t - 1.0) - K * ((t - 1.0) - T * (1.0 - np.exp(-(t - 1.0) / T)))
    m_I1 = res["pid.m_I"][np.searchsorted(res.t, 1.0)]
    exact_mI = np.where(t <= 40.0, m_I1 + 0.8 / 5.0 * integral, np.nan)
    sel = t < 40.0
    assert np.max(np.abs(res["pid.m_I"][sat][sel] - exact_mI[sel])) < 1e-5 * exact_mI[sel].max()
    assert np.max(np.abs(res["G.y"][sat] - y)) < TOL
    # wound up: m_I(40 s) = 0.16 (3 * 39 - 2 (39 - 10 (1 - e^-3.9))) = 9.4, nine times z_max
    assert res["pid.m_I"].max() > 9.0
    assert leave > 40.0 + 20.0  # it stays saturated long after the set point came down


def test_bumpless_transfer_from_manual():
    # manual (active = 0) until 100 s with z = 0.3, then automatic: the integral has
    # tracked z for 100 s (T_t = T_i = 5 s: exp(-20) of the initial mismatch left)
    plant = loop(
        1.0,
        Kp=0.8,
        T_i=5.0,
        z_min=0.0,
        z_max=1.0,
        active=Step(100.0, 0.0, 1.0),
        z_manual=0.3,
    )
    res = run(plant, 200.0)
    k = int(np.flatnonzero(res.t == 100.0)[0])  # the row after the time event
    assert res["pid.z"][k - 1] == pytest.approx(0.3, abs=1e-12)  # manual
    assert abs(res["pid.z"][k] - 0.3) < TOL  # automatic: no bump
    # and then it controls: y -> w = 1
    # closed-loop poles: roots of T s^2 + (1 + K Kp) s + K Kp/T_i, real part -0.13 1/s:
    # after 100 s in automatic e^-13 (2e-6) of the initial error 0.4 is left
    assert res["G.y"][-1] == pytest.approx(1.0, abs=1e-5)


def test_per_unit_gain_equals_engineering_gain():
    common = dict(T_i=6.0, z_min=-5.0, z_max=5.0)
    # both runs output on one grid from their own dense output: the two runs' tolerances
    # differ (measured_span sets the scales), so their steps do, and linear interpolation
    # between one run's steps would add its own error (4e-6 here) to the comparison
    grid = np.linspace(0.0, 20.0, 401)
    a = run(loop(Step(1.0, 0.0, 1.0), Kp=0.4, **common), 20.0, t_eval=grid)
    # Kp = Kc * output_span / measured_span = 0.2 * 10 / 5
    b = run(loop(Step(1.0, 0.0, 1.0), Kc=0.2, measured_span=5.0, **common), 20.0, t_eval=grid)
    assert np.array_equal(a.t, b.t)
    assert np.max(np.abs(b["G.y"] - a["G.y"])) < TOL


def test_default_tracking_time():
    assert PIDController("c", Kp=1.0, T_i=9.0, T_d=4.0, setpoint=0.0).T_t == 6.0
    assert PIDController("c", Kp=1.0, T_i=9.0, setpoint=0.0).T_t == 9.0
    assert math.isclose(PIDController("c", Kp=1.0, T_i=9.0, T_t=2.0, setpoint=0.0).T_t, 2.0)


@pytest.mark.parametrize(
    "params, words",
    [
        (dict(setpoint=0.0), "give the gain as Kp"),
        (dict(Kp=1.0, Kc=1.0, measured_span=1.0, setpoint=0.0), "one of them"),
        (dict(Kc=1.0, setpoint=0.0), "measured_span"),
        (dict(Kp=1.0, setpoint=0.0, active=Step(5.0, 1.0, 0.0)), "z_manual"),
        (dict(Kp=1.0, setpoint=0.0, z_min=1.0, z_max=0.0), "z_max must be greater"),
    ],
)
def test_bad_parameters_are_named(params, words):
    with pytest.raises(PlantError, match=words):
        PIDController("c", **params)


def test_tracking_input_bounds_the_integral_at_an_external_limit():
    # the actuator (a Limiter [0, 1]) saturates outside the controller, whose own
    # limits are wide; with tracking = true the back-calculation uses the actuator
    # position: dm_I/dt = Kp e/T_i + (track - v)/T_t = (1 - m_I)/T_i in saturation
    from dnasim.library.signal_blocks import Limiter

    plant = Plant("loop")
    plant.add(FirstOrderLag("G", T=T, k=K))
    plant.add(Limiter("act", y_min=0.0, y_max=1.0))
    plant.add(
        PIDController(
            "pid",
            setpoint=_Steps(),
            Kp=0.8,
            T_i=5.0,
            z_min=-100.0,
            z_max=100.0,
            tracking=True,
            error_sign="setpoint-measured",
            measured_nominal=1.0,
        )
    )
    plant.link("pid.z", "act.u")
    plant.link("act.y", "G.u")
    plant.link("act.y", "pid.track")
    plant.link("G.y", "pid.measured")
    res = run(plant, 200.0)
    enter, leave = [e["t"] for e in res.events if e["name"] == "act.upper"][:2]
    assert enter == 1.0 and leave == 40.0
    sat = (res.t > enter) & (res.t < leave)
    t0, m0 = res.t[sat][0], res["pid.m_I"][sat][0]
    exact = 1.0 + (m0 - 1.0) * np.exp(-(res.t[sat] - t0) / 5.0)
    assert np.max(np.abs(res["pid.m_I"][sat] - exact)) < TOL
