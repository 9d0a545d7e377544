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
#: day one of them passes, the suite says so and the mark must go. Diagnosis (boil
#: branch, boiling_10bar): without the phase switches dnasim's BDF and IDA on the same
#: residual both stop at t = 19.642 s, where the outlet volume first reaches h'(p)
#: (Newton rate 2.5e4 at h = 1.2e-9 s; IDA "convergence test failed too many
#: times"): the kink of rho(p, h) alone defeats the modified Newton of both. With the
#: switches the first crossings (volumes 19 to 11) are located and passed; a volume
#: that falls back to the liquid line is then located again and again (Zeno). A C1
#: blend of v and T over +-1 kJ/kg (tried on the boil branch, not kept) removes the kink but the run
#: stops at the band's liquid edge: in liquid dp/dh at fixed M is 310 Pa per J/kg and
#: a face passes 0.09 kg/s per Pa, so any curvature of rho in h reaches the flows
#: amplified ~30 kg/s per J/kg and the corrector of the flows does not converge.
#: Consistent with that: the same plant with k = 1e6 instead of 1e5 (switches on, no
#: blend) runs from 0 to 40 s through both saturation lines (5111 steps, 387 located
#: crossings, 30 re-initialisations), where k = 1e5 stops at 22.83 s.
NOT_YET = {
    "boiling_60bar": "stops at ~38.43 s in the moving boiling front: the crossings of volumes 19 "
    "to 2 (26.6 to 35.9 s) are located and passed, but 13321 of its 13904 steps (median 1e-4 s) "
    "fall between the crossings of volumes 4 and 3 (32.5 to 34.5 s)",
    "boiling_10bar": "stops at ~22.83 s: volume 11, boiling since 20.84 s, falls back to the "
    "saturated-liquid line and the crossing is located 7 times in 5e-4 s (Newton fails at "
    "h = 1e-10 s)",
    "boiling_190bar": "stops at ~34.9 s at the saturated-liquid line (Newton too slow)",
    "condensing_pipe": "stops at ~55.21 s: every saturated-vapour crossing (volumes 0 to 19, 25.4 "
    "to 45.4 s) is passed; the first saturated-liquid crossing (volume 19) is located 6 times in "
    "1.2e-8 s, then the step size falls to round-off",
}


def _param(case):
    marks = [pytest.mark.field_slow] if case.slow else []
    if case.name in NOT_YET:
        marks.append(pytest.mark.xfail(reason=NOT_YET[case.name], strict=True))
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

    from dnasim.plantfile import load

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
