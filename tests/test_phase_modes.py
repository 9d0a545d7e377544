"""Phase branches of IF97 water and the phase modes of channel volumes.

A volume's equation of state is kinked on the saturation lines (d rho/dh|_p jumps by a
factor ~300 on the saturated-liquid line at 10 bar). Each volume keeps its phase as a
discrete mode and is evaluated on that mode's branch, continued smoothly past the line,
until the crossing is located (dnasim.library.submodels.channel, "Phase modes"); the branches
come from dnasim.media.if97_numba.ph_branch_scalar.
"""

import numpy as np
import pytest

from dnasim.library.submodels.channel import AUTO, DOME, LIQUID, VAPOUR
from dnasim.media import if97_numba as NB
from dnasim.media.registry import get_medium

PRESSURES = [1e5, 10e5, 60e5, 190e5]  # [Pa] from 1 bar to 2.2 MPa below the critical point


def _rho(p, h, branch):
    return NB.ph_branch_scalar(p, h, branch)[1]


@pytest.mark.parametrize("p", PRESSURES)
def test_branches_equal_the_true_state_on_their_own_side(p):
    hl, hv = NB.saturation_scalar(p)
    for h, branch in [(hl - 5e3, LIQUID), (0.5 * (hl + hv), DOME), (hv + 5e3, VAPOUR)]:
        # the same equations, the same solve: identical to the last bit
        np.testing.assert_array_equal(NB.ph_branch_scalar(p, h, branch), NB.ph_scalar(p, h))


@pytest.mark.parametrize("p", PRESSURES)
def test_branches_meet_on_the_saturation_lines(p):
    # At h = h'(p) the liquid branch and the two-phase formula are the same state (the
    # saturated liquid); likewise the vapour branch and the dome at h''. 1e-12: the
    # kernel's (p, h) solve converges to ~1e-13 relative.
    hl, hv = NB.saturation_scalar(p)
    assert _rho(p, hl, LIQUID) == pytest.approx(_rho(p, hl, DOME), rel=1e-12)
    assert _rho(p, hv, VAPOUR) == pytest.approx(_rho(p, hv, DOME), rel=1e-12)
    assert NB.ph_branch_scalar(p, hl, LIQUID)[0] == pytest.approx(NB._tsat(p), abs=1e-9)


@pytest.mark.parametrize("p", PRESSURES)
def test_continued_branches_are_smooth_across_the_line(p):
    # The liquid branch past h' (metastable liquid) has the liquid's slope on both sides
    # of the line: its d rho/dh changes by less than 1 % over +-2 kJ/kg, while the true
    # state's slope jumps (the kink the modes avoid): by a factor of ~300 at 10 bar, ~2.7
    # at 190 bar where the dome narrows; asserted: more than 2.
    hl, hv = NB.saturation_scalar(p)
    d = 2e3

    def slope(h, branch):
        return (_rho(p, h + 1.0, branch) - _rho(p, h - 1.0, branch)) / 2.0

    below, above = slope(hl - d, LIQUID), slope(hl + d, LIQUID)
    assert above == pytest.approx(below, rel=1e-2)
    assert abs(slope(hl + d, AUTO)) > 2 * abs(slope(hl - d, AUTO))
    # the dome continued below h' (x < 0) and above h'' (x > 1) is the mixture formula
    x = NB.ph_branch_scalar(p, hl - d, DOME)[5]
    assert x == pytest.approx(-d / (hv - hl), rel=1e-12)
    # metastable liquid is hotter than T_sat, metastable vapour colder
    assert NB.ph_branch_scalar(p, hl + d, LIQUID)[0] > NB._tsat(p)
    assert NB.ph_branch_scalar(p, hv - d, VAPOUR)[0] < NB._tsat(p)


def test_states_with_branches_matches_the_scalar_kernel():
    water = get_medium("Water")
    if not water.phase_branches:
        pytest.skip("numba kernel not available")
    p = np.array([10e5, 10e5, 60e5, 60e5, 300e5])
    hl, _ = NB.saturation_arrays(p[:4])
    h = np.array([hl[0] + 500.0, hl[1] - 500.0, hl[2] + 500.0, 2.0e6, 1.8e6])
    branch = np.array([LIQUID, DOME, AUTO, VAPOUR, LIQUID])  # above p_c: the usual state
    r = water.states(p, h, branch=branch)
    for i in range(p.size):
        ref = NB.ph_branch_scalar(p[i], h[i], branch[i])
        assert r.rho[i] == ref[1] and r.T[i] == ref[0]
    assert r.rho[4] == water.state(p[4], h[4]).rho


def test_pipe_volumes_start_in_the_mode_of_their_state_and_switch_at_the_line():
    from dnasim import load_plant
    from dnasim.compilation.compiler import compile as compile_plant
    from dnasim.start.initial import initial_values

    plant = load_plant("tests/field/boiling_10bar.toml")
    system = compile_plant(plant)
    initial_values(system, 0.0, "steady")
    # the steady start is subcooled water all along the tube (150 degC in, wall 160 degC)
    assert list(system.modes["tube"]["phase"]) == [LIQUID] * 20
    switch = next(s for s in system.events if "phase" in s.name)
    block = system.block("tube")
    x = block.local(np.zeros(system.n))
    switch.switch.action(0.0, x, x, np.array([2 * 19, 2 * 18 + 0]))  # liquid -> dome
    assert system.modes["tube"]["phase"][19] == DOME
    assert system.modes["tube"]["phase"][18] == DOME
    switch.switch.action(0.0, x, x, np.array([2 * 19 + 1]))  # dome -> vapour
    assert system.modes["tube"]["phase"][19] == VAPOUR
