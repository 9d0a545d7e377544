"""Vector equations (``Equation(size=n)``): n scalar rows declared once, with each
row's own dependencies and one residual function for the whole block."""

import math

import numpy as np
import pytest

from dnasim.core.errors import PlantError
from dnasim.library import Component, Equation, Variable
from dnasim.plant.plant import Plant
from dnasim.solver import solve_dae


class _Cascade(Component):
    """Test component: n first-order lags in series, z'[0] = -z[0],
    z'[i] = z[i-1] - z[i]; from z(0) = (1, 0, ..., 0) the closed form is
    z[i](t) = t^i e^-t / i!. ``wrong`` makes the residual one value short."""

    REGISTER = False
    USES_MEDIUM = False

    def __init__(self, name, n, wrong=False):
        self.n_lags, self.wrong = n, wrong
        super().__init__(name)

    def variables(self):
        return [Variable("z", "1", 1.0, self.n_lags, "lag output")]

    def equations(self):
        n = self.n_lags

        def lag(t, x, xp):
            z = x["z"]
            inflow = np.concatenate(([0.0], z[:-1]))
            r = xp["z"] - (inflow - z)
            return r[:-1] if self.wrong else r

        return [
            Equation(
                "lag",
                size=n,
                y=lambda i: (f"z[{i}]",) if i == 0 else (f"z[{i - 1}]", f"z[{i}]"),
                yp=lambda i: (f"z[{i}]",),
                doc="z'[i] = z[i-1] - z[i]",
                unit="1/s",
                residual=lag,
            )
        ]


def test_rows_of_scalar_and_vector_equations():
    scalar = Equation("flow", y=("m", "inlet.p"))
    assert scalar.n_rows == 1 and scalar.rows() == [("flow", ("m", "inlet.p"), ())]
    vec = Equation("mass", size=3, y=lambda i: (f"m[{i}]", f"m[{i + 1}]"), yp=("M_total",))
    assert vec.n_rows == 3
    assert vec.rows()[2] == ("mass[2]", ("m[2]", "m[3]"), ("M_total",))  # tuple: every row


def test_vector_equation_gives_names_sparsity_and_residual():
    n = 4
    plant = Plant("cascade")
    plant.add(_Cascade("c", n))
    dae = plant.compile()
    assert dae.eq_names == [f"c.lag[{i}]" for i in range(n)]
    col = {name: j for j, name in enumerate(dae.names)}
    py, pyp = dae.pattern_y.toarray(), dae.pattern_yp.toarray()
    for i in range(n):
        deps = {f"c.z[{i}]"} | ({f"c.z[{i - 1}]"} if i else set())
        assert {dae.names[j] for j in np.flatnonzero(py[i])} == deps
        assert np.flatnonzero(pyp[i]).tolist() == [col[f"c.z[{i}]"]]
    y0 = np.zeros(n)
    y0[0] = 1.0
    yp0 = -dae.residual(0.0, y0, np.zeros(n))  # F = y' - f(y): y'0 = f(y0)
    res = solve_dae(
        dae.residual,
        (0.0, 2.0),
        y0,
        yp0,
        algebraic=dae.algebraic,
        rtol=1e-8,
        atol=1e-10,
        jac_sparsity=dae.jac_sparsity,
        dense_output=False,
    )
    exact = [2.0**i * math.exp(-2.0) / math.factorial(i) for i in range(n)]
    # rtol 1e-8 per step over ~100 steps: the global error stays below 1e-6
    np.testing.assert_allclose(res.y[:, -1], exact, rtol=0, atol=1e-6)


def test_vector_residual_of_wrong_length_names_the_equation():
    plant = Plant("cascade")
    plant.add(_Cascade("c", 3, wrong=True))
    dae = plant.compile()
    with pytest.raises(
        PlantError, match=r"'c'.*equation 'lag' returned 2 residuals but declares 3"
    ):
        dae.residual(0.0, np.zeros(3), np.zeros(3))
