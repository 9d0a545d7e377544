"""The steady start's guess (``Component.steady_guess``): a heated pipe marches its
steady heat balance from the inlet, a mixing volume mixes its inflows.

Air is the media helper's ideal gas with constant cp, for which the march is the
closed form of the log-mean pipe (T_i - T_w = (T_a - T_w) exp(-kA_i / (m cp)))."""

import math
from pathlib import Path

import numpy as np
import pytest

from dnasim.library import MassFlowBoundary, Pipe, PressureBoundary, Valve
from dnasim.media import get_medium
from dnasim.plant.plant import Plant
from dnasim.plant.plantfile import load
from dnasim.start.guess import initial_guess
from dnasim.start.initial import initial_values

PLANTS = Path(__file__).resolve().parent.parent / "plants"
CP = get_medium("Air").state(1e5, 3e5).cp


def heated_air_pipe(n, kA=150.0, T_in=600.0, T_wall=300.0, m=0.1):
    """A mass-flow source at m = m_nominal into a pipe with a fixed wall, then a valve
    to a pressure sink: the steady flow is the guessed flow m_nominal."""
    plant = Plant("heated", medium="Air")
    plant.add(MassFlowBoundary("src", m=m, T=T_in, m_nominal=m))
    plant.add(Pipe("pipe", V=0.08, kA=kA, k=1.2e5, T_wall=T_wall, n_volumes=n, m_nominal=m))
    plant.add(Valve("valve", C=3.2e-4, opening=1.0, m_nominal=m))
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
    return plant.compile()


def volume_temperatures(system, y):
    medium = get_medium("Air")
    b = system.block("pipe")
    x = b.local(y)
    return np.array([medium.state(p, h).T for p, h in zip(x["p_v"], x["h_v"], strict=True)])


@pytest.mark.parametrize("n", [1, 5])
def test_heated_pipe_guess_is_the_exponential_closed_form(n):
    # Constant cp: h_i - h_a = cp (T_i - T_a), and the march's step
    # (kA_i/m)(T_w - T_a)(1 - exp(-NTU))/NTU = cp (T_w - T_a)(1 - exp(-NTU)) gives
    # T_i - T_w = (T_a - T_w) exp(-NTU) exactly: equal to the closed form up to the
    # round-off of the ideal gas's T(h) through n steps (1e-9 K is 3e-12 relative)
    T_w, T_in, kA, m = 300.0, 600.0, 150.0, 0.1
    system = heated_air_pipe(n, kA, T_in, T_w, m)
    y = initial_guess(system, 0.0, steady=True)
    T = volume_temperatures(system, y)
    ntu_i = kA / n / (m * CP)
    exact = T_w + (T_in - T_w) * np.exp(-ntu_i * (np.arange(n) + 1.0))
    np.testing.assert_allclose(T, exact, rtol=0, atol=1e-9)
    # and it is the steady state the start finds: the log-mean pipe has no
    # discretisation error (tests/test_plant_closed_forms.py); what differs is the
    # start's Newton tolerance (1e-10 relative steps, 1e-7 K at 600 K) and the LMTD's
    # softplus regularisation (dT_reg = 1 K, exp(-dT/dT_reg) < 1e-100 here)
    y_steady, _ = initial_values(system, 0.0, "steady")
    np.testing.assert_allclose(volume_temperatures(system, y_steady), exact, rtol=0, atol=1e-7)
    # the guessed heat flows are the march's: Q_i = -m (h_i - h_a) [W], sum = m cp dT
    Q = system.block("pipe").local(y)["Q"]
    assert math.isclose(float(np.sum(Q)), m * CP * (T_in - exact[-1]), rel_tol=1e-12)


def test_given_start_guess_is_unchanged_by_the_steady_guess():
    # a given start takes its initial state from initial_guess alone: steady_guess
    # must not run there (steady=False), so the pipe keeps its guess interpolated
    # linearly from the inlet to the outlet node's h (equal steps, to round-off of
    # 3e5 J/kg: 1e-9 J/kg), not the march's geometric steps
    system = heated_air_pipe(4)
    b = system.block("pipe")
    h_given = b.local(initial_guess(system, 0.0))["h_v"]
    steps = np.diff(np.concatenate(([b.local(initial_guess(system, 0.0))["inlet.h"]], h_given)))
    np.testing.assert_allclose(steps, steps[0], rtol=0, atol=1e-9)
    h_steady = b.local(initial_guess(system, 0.0, steady=True))["h_v"]
    assert not np.allclose(h_steady, h_given)


def _scaled_distance(system, y, y_star):
    """Largest |y - y*| in units of each variable's scale max(nominal, |y*|) [-]."""
    scale = np.maximum(system.nominal, np.abs(y_star))
    return np.abs(y - y_star) / scale


def test_superheater_line_guess_is_nearer_its_steady_state():
    # three superheaters heated by fixed walls at 560-600 degC, two attemperators:
    # the old guess had every node at the boiler's 360 degC; the march and the
    # mixing put the enthalpies of the heated pipes and the attemperators near
    # the steady state. Measured on the enthalpies of all volumes (h_v).
    system = load(PLANTS / "superheater_line.toml").plant.compile()
    y_star, _ = initial_values(system, 0.0, "steady")
    old = initial_guess(system, 0.0)
    new = initial_guess(system, 0.0, steady=True)
    h = np.array([".h_v" in nm for nm in system.names])
    d_old = _scaled_distance(system, old, y_star)[h]
    d_new = _scaled_distance(system, new, y_star)[h]
    # the heated pipes' outlets were 180 K too cold (0.15 of h); the march leaves
    # the error of the guessed flow and spray (m_nominal, no spray): a few percent
    assert d_old.max() > 0.1
    assert d_new.max() < 0.05
    assert np.linalg.norm(d_new) < 0.3 * np.linalg.norm(d_old)
