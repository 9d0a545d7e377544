"""The seed's steam temperature control example (10.2.3): mixing, the controller's
saturation switch, and a cross-check against SUNDIALS IDA on the same residual."""

import numpy as np
import pytest

from dnasim.plant.examples import attemperator_plant
from dnasim.run.simulation import IDA
from dnasim.start.initial import initial_values


@pytest.fixture(scope="module")
def plant():
    return attemperator_plant()


@pytest.fixture(scope="module")
def result(plant):
    return plant.simulate(400.0, start="steady", rtol=1e-6)


def test_steady_outlet_enthalpy_is_mass_weighted_mix(plant):
    dae = plant.compile()
    y, yp = initial_values(dae, 0.0, "steady")
    v = dict(zip(dae.names, y, strict=False))
    ms, mw = v["att.m_steam"], v["att.m_water"]
    mix = (ms * v["steam_in.h"] + mw * v["spray.h"]) / (ms + mw)
    # Exact identity of the steady equations (dM/dt = dU/dt = 0); the damped
    # Newton stops at relative steps below 1e-10, so 1e-9 relative is round-off
    # level for this solve.
    assert abs(v["mixed.h"] - mix) < 1e-9 * mix
    assert abs(v["att.m_out"] - (ms + mw)) < 1e-9 * (ms + mw)
    # and the controller is in range, at its set point
    assert 0.0 < v["pi.z"] < 1.0
    assert abs(v["att.T"] - (450.0 + 273.15)) < 1e-6


def test_controller_saturates_and_switch_is_located(result):
    assert result.success
    events = [e for e in result.events if e["name"] == "pi.upper"]
    assert len(events) == 1, result.events
    ev = events[0]
    assert ev["component"] == "pi" and ev["switch"] == "upper"
    # Table 10.1: located to |switch| <= 1e-10 within a handful of iterations
    assert len(ev["iterates"]) <= 8
    assert abs(ev["iterates"][-1][1]) <= 1e-10
    t_s = ev["t"]
    assert 150.0 < t_s < 300.0
    after = result.t > t_s + 1e-9
    assert np.allclose(result["pi.z"][after], 1.0, atol=1e-12)
    # without anti-windup the demanded output keeps rising after saturation (Fig. 10.6)
    v = result["pi.m_p"] + result["pi.m_I"]
    assert v[-1] > 1.1
    # the outlet stays above the set point: the spray valve is fully open
    assert result["att.T"][-1] > 450.0 + 273.15 + 5.0


def test_restart_at_order_one_after_the_switch(result):
    ev = next(e for e in result.events if e["name"] == "pi.upper")
    hist = result.steps
    first_after = hist[hist[:, 0] > ev["t"] + 1e-12][0]
    assert first_after[2] == 1  # Fig. 10.7: the integration restarts at order 1
    before = hist[hist[:, 0] <= ev["t"]]
    assert before[:, 2].max() > 1  # and it had climbed above order 1 before


def test_anti_windup_holds_the_integrator():
    res = attemperator_plant(anti_windup=True).simulate(400.0, start="steady", rtol=1e-6)
    ev = next(e for e in res.events if e["name"] == "pi.upper")
    after = res.t > ev["t"] + 1e-9
    m_I = res["pi.m_I"][after]
    # dm_I/dt = 0 while saturated: constant to the integrator's tolerance
    assert np.ptp(m_I) < 1e-9


def test_ida_cross_check(plant):
    t_eval = np.linspace(0.0, 400.0, 81)
    ours = plant.simulate(400.0, start="steady", rtol=1e-7, atol_scaled=1e-8, t_eval=t_eval)
    # IDA at a tighter tolerance: at rtol 1e-7 its own error on this plant (0.015 K
    # in att.T during the ramp, measured against IDA at 1e-10) is larger than ours
    # (6e-6 K against ours at 1e-10), so it would test IDA, not us.
    ida = plant.simulate(400.0, start="steady", solver=IDA(rtol=1e-9, atol_scaled=1e-10))
    assert ours.success and ida.success
    # the switch times agree (IDA's root finder works to its own tolerance ~1e-4 s)
    t_ours = next(e["t"] for e in ours.events if e["name"] == "pi.upper")
    t_ida = next(e["t"] for e in ida.events if e["name"] == "pi.upper")
    assert abs(t_ours - t_ida) < 1e-2
    # trajectories at common times: global errors of both are some tens of times
    # the local tolerance 1e-7; 1e-4 relative (0.07 K on 740 K) leaves room for
    # that and the slightly different switch times.
    for name in ["att.T", "pi.m_I", "spray_valve.m", "att.M"]:
        ref = np.interp(ours.t, ida.t, ida[name])
        scale = np.max(np.abs(ida[name]))
        assert np.max(np.abs(ours[name] - ref)) < 1e-4 * scale, name
