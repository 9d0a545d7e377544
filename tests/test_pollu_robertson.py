"""The Test Set problems added for benchmarks/solver_vs_peers.py (POLLU, Robertson to
t = 1e11): their definitions reproduce the published reference solutions, and
dnasim's solver reaches them."""

from __future__ import annotations

import numpy as np
from problems import (
    POLLU_REF,
    POLLU_T_END,
    POLLU_Y0,
    ROBERTSON_1E11_REF,
    ROBERTSON_Y0,
    ROBERTSON_YP0,
    as_residual,
    pollu_rhs,
    robertson,
)
from scipy.integrate import solve_ivp

from dnasim import solve_dae


def scd(y, ref, floor):
    """-log10 max relative error over the components above floor (Test Set's scd)."""
    m = np.abs(ref) > floor
    return float(-np.log10(np.max(np.abs(y[m] - ref[m]) / np.abs(ref[m]))))


def test_pollu_definition_matches_the_published_reference():
    # scipy's Radau (nobody here wrote it) at rtol 1e-10 on the transcribed equations: a
    # wrong rate constant or sign would cost more than the 7 digits asked (measured 11.3)
    sol = solve_ivp(pollu_rhs, (0, POLLU_T_END), POLLU_Y0, method="Radau", rtol=1e-10,
                    atol=1e-16)  # fmt: skip
    assert scd(sol.y[:, -1], POLLU_REF, 1e-12) > 7.0


def test_dnasim_solves_pollu_and_robertson_to_1e11():
    r = solve_dae(as_residual(pollu_rhs), (0, POLLU_T_END), POLLU_Y0, None, rtol=1e-7,
                  atol=1e-10, throw=True)  # fmt: skip
    # rtol 1e-7 gives 6.5 digits (measured); 4.5 leaves room for step-size changes
    assert scd(r.y[:, -1], POLLU_REF, 1e-10) > 4.5
    r = solve_dae(robertson, (0, 1e11), ROBERTSON_Y0, ROBERTSON_YP0, algebraic=[2],
                  rtol=1e-8, atol=np.array([1e-14, 1e-18, 1e-14]), throw=True)  # fmt: skip
    # y2 = 8e-14 is the hardest component; 6.2 digits at rtol 1e-8 (measured), 3 asked
    assert scd(r.y[:, -1], ROBERTSON_1E11_REF, 1e-20) > 3.0
