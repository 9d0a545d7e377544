"""Field tests (issue 7): plant files written as a user writes them, run to the end
through the CLI and judged against physics (see tests/field_checks.py).

Each plant in tests/field/ must finish (exit 0, t_end reached), close its mass and
energy balances over the whole run to 1e-6 of the throughput, and pass its own
checks (closed forms, hand calculations with CoolProp's IF97, maximum principle).
The 1000-volume pipes carry the marker ``field_slow``: ``pytest -m field_slow`` runs
them alone, ``-m "not field_slow"`` skips them; CI runs everything.
"""

import pytest
from field_checks import CASES, evaluate, run_plant

#: plants that do not yet run to the end (issue 7 stays open for them). strict: the
#: day one of them passes, the suite says so and the mark must go. How the boiling
#: plants came to run (measured on boiling_10bar, which stopped at 22.83 s): each pipe
#: volume keeps its phase as a discrete mode and is evaluated on that branch, continued
#: past the saturation line, between located crossings (no kink inside a step); and the
#: corrector falls back to full Newton when modified Newton with a fresh matrix converges
#: but too slowly (the flow next to a boiling volume is predicted ~3 kg/s off: liquid
#: pressures move by 1e9 Pa per kg). Either alone still stops at 22.83 s.
NOT_YET: dict[str, str] = {
    # Passed while the output perturbed the integration's path (the IF97 memos, warm-
    # started from output evaluations, moved the steps by round-off); since the output
    # is evaluated aside (physics.aside, 2026-12-02) the path is the output-free one,
    # and on it the run stops at 103.24 s (h = 9.2e-10 s, Newton rate 4.25 on n_check.p,
    # n_check.h, n_discharge.h, n_feed.h: the no-flow node between the pump and the
    # shut check valve, issue 20 item 4), the point at which the stag2 experiment's
    # perturbation also stopped it.
    "feed_line_level_control": "stops at 103.24 s on the output-free path (no-flow node)",
}
#: condensing_pipe left this list on branch merge10: it stopped at ~57.6 s where the
#: collapsing steam draws condensate back through the outlet valve (the outlet node's
#: enthalpy swinging between the tube's 1.2 MJ/kg and the header's 0.63 MJ/kg within the
#: upwind regularisation, full Newton not converging). On merge10 it runs to the end and
#: passes its checks owing to the corrector's last attempt from the algebraic unknowns'
#: last accepted values (dnasim.solver.bdf ``_last_chance``): without that attempt the
#: same branch stops at 55.2 s (a re-initialisation outside IF97's domain; measured).


def _param(case):
    marks = [pytest.mark.field_slow] if case.slow else []
    if case.name in NOT_YET:
        # not strict: the stop is at round-off's mercy (a knife-edge), either way
        marks.append(pytest.mark.xfail(reason=NOT_YET[case.name], strict=False))
    return pytest.param(case, id=case.name, marks=marks)


@pytest.mark.parametrize("case", [_param(c) for c in CASES])
def test_field_plant(case, tmp_path):
    run = run_plant(case.name, tmp_path / case.name)
    checks = evaluate(case, run)
    failed = [f"{name}: {detail}" for name, ok, detail in checks if not ok]
    assert not failed, f"{case.name}:\n  " + "\n  ".join(failed)


def test_balance_helper_sees_a_leak():
    # The balance check itself must be able to fail: a synthetic record of the steam
    # network (feed 40 kg/s in, 39 kg/s out, 1 kg/s stored in the header) closes to
    # round-off; 1 g missing from the storage is seen as an error of 1 g / throughput.
    import numpy as np
    import pandas as pd
    from field_checks import Run, balances, into_sign, plant_path

    from dnasim.plant.plantfile import load

    plant = load(plant_path("steam_network_step")).plant
    t = np.linspace(0.0, 10.0, 11)
    h = 3.4e6
    df = pd.DataFrame(
        {
            "time": t,
            "feed.M_passed": into_sign(plant, "feed") * 40.0 * t,
            "feed.H_passed": into_sign(plant, "feed") * 40.0 * h * t,
            "turbine.M_passed": into_sign(plant, "turbine") * -39.0 * t,
            "turbine.H_passed": into_sign(plant, "turbine") * -39.0 * h * t,
            "header.M[0]": 100.0 + 1.0 * t,
            "header.U[0]": 100.0 * h + 1.0 * h * t,
        }
    )
    run = Run("synthetic", 0, "", df, 10, 0.0, 10.0, plant)
    bal = balances(run)
    assert bal.mass_err < 1e-15 and bal.energy_err < 1e-15  # exact data, round-off only
    df.loc[df.index[-1], "header.M[0]"] -= 1e-3
    bal = balances(run)
    assert abs(bal.mass_err - 1e-3 / 790.0) < 1e-12  # scale: sum_b max_t |M_passed_b| = 790 kg
