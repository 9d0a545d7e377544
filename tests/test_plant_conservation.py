"""Mass and energy balances of a whole network in a transient with an inlet step."""

import numpy as np

from dnasim.core.timefunctions import Step
from dnasim.library import PressureBoundary
from dnasim.plant.examples import air_pipe_plant

RTOL = 1e-7


def stepped_air_pipe():
    plant = air_pipe_plant(n_volumes=3)
    # replace the source by one whose temperature steps from 600 K to 700 K at t = 200 s
    src = plant.components["source"]
    plant.components["source"] = PressureBoundary(
        "source", p=2.0e5, T=Step(200.0, 600.0, 700.0), m_nominal=src.params["m_nominal"]
    )
    plant._dae = None
    return plant


def test_mass_and_energy_balance_to_solver_tolerance():
    plant = stepped_air_pipe()
    res = plant.simulate(1000.0, start="given", rtol=RTOL, atol_scaled=1e-8)
    assert res.success
    assert 200.0 in res.t  # the step is a tstop: the integrator lands on it
    stored_mass = res["pipe1.M_total"] - res["pipe1.M_total"][0]
    passed_mass = res["source.M_passed"] + res["exhaust.M_passed"]  # both into the plant
    stored_energy = (res["pipe1.U_total"] + res["pipe1.E_wall"]) - (
        res["pipe1.U_total"] + res["pipe1.E_wall"]
    )[0]
    passed_energy = res["source.H_passed"] + res["exhaust.H_passed"]
    throughput_mass = res["source.M_passed"][-1]
    throughput_energy = res["source.H_passed"][-1]
    # M, U, T_w and the boundaries' running integrals are all states of one BDF
    # solution; a linear invariant (stored + passed) is kept by BDF up to the
    # Newton tolerance, which the solver holds well below rtol. Bound: rtol times
    # the throughput.
    assert np.max(np.abs(stored_mass - passed_mass)) < RTOL * throughput_mass
    assert np.max(np.abs(stored_energy - passed_energy)) < RTOL * throughput_energy
    # The transient is real: mass left the pipe while it heated, energy was stored.
    assert stored_mass[-1] < -0.01 * res["pipe1.M_total"][0]
    assert stored_energy[-1] > 1e6


def test_running_integrals_match_quadrature_of_boundary_flows():
    # Independent of the accumulators: integrate the boundary flows over the
    # output points by the trapezoidal rule. Its error is O(h^2 m''), so the
    # comparison is only to 1e-3 of the throughput, on dense output points.
    plant = stepped_air_pipe()
    t_eval = np.concatenate([np.linspace(0, 200, 2001), np.linspace(200, 1000, 4001)[1:]])
    res = plant.simulate(1000.0, start="given", rtol=RTOL, atol_scaled=1e-8, t_eval=t_eval)
    m_in = np.trapezoid(res["source.m"], res.t)
    m_out = -np.trapezoid(res["exhaust.m"], res.t)  # exhaust.m < 0: out of the plant
    stored = res["pipe1.M_total"][-1] - res["pipe1.M_total"][0]
    assert abs(stored - (m_in - m_out)) < 1e-3 * m_in
    h_in = np.trapezoid(res["source.m"] * res["inlet.h"], res.t)
    h_out = -np.trapezoid(res["exhaust.m"] * res["exit.h"], res.t)
    e_stored = (res["pipe1.U_total"] + res["pipe1.E_wall"])[-1] - (
        res["pipe1.U_total"] + res["pipe1.E_wall"]
    )[0]
    assert abs(e_stored - (h_in - h_out)) < 1e-3 * abs(h_in)
