"""The Nordsieck array of a fixed-leading-coefficient BDF method, and its algebra.

The Nordsieck array of order q at time t_n with step h holds, row by row,

    z[j] = h**j * y^(j)(t_n) / j!        j = 0, 1, ..., q

for every component of y (shape ``(q + 1, n)``). It is a Taylor polynomial in
the scaled variable s = (t - t_n) / h:

    y(t_n + s h) ~= sum_j z[j] s**j,    h y'(t_n + s h) ~= sum_j j z[j] s**(j-1).

Prediction (seed eq. 10.10) evaluates that polynomial one step ahead: the new
array is P z with P the upper-triangular Pascal matrix, P[i, j] = C(j, i).

Correction: the BDF of order q in Nordsieck form updates every row by a
multiple of one vector Delta = y_n - y_pred,

    z_n = z_pred + l Delta,     l = coefficients of Lambda(x) = prod_{i=1..q} (1 + x / i)

(Hairer & Wanner II, sec. III.6; the constant-step ``l`` vector of LSODE and
CVODE). With l[0] = 1 the corrected derivative is

    y'_n = z_pred[1] / h + (l[1] / h) (y_n - y_pred),   l[1] = sum_{i=1..q} 1/i,

so the Newton iteration matrix is dF/dy + (l[1] / h) dF/dy'.

Error constants. For the normalised BDF the local error is
C_q h^(q+1) y^(q+1) with C_q = -1 / ((q + 1) l[1]); the predictor's is
h^(q+1) y^(q+1). Milne's estimate (seed eq. 10.7) of the local error is then

    LTE ~= C / (C - C_pred) * (y_C - y_P) = Delta / ((q + 1) l[1] + 1).

A step-size change by the factor r scales row j by r**j (seed eq. 10.9).
"""

from __future__ import annotations

from functools import cache
from math import comb, factorial

import numpy as np

MAX_ORDER = 5


@cache
def pascal_matrix(q: int) -> np.ndarray:
    """Upper-triangular Pascal matrix of size q + 1: P[i, j] = C(j, i) for j >= i."""
    p = np.zeros((q + 1, q + 1))
    for i in range(q + 1):
        for j in range(i, q + 1):
            p[i, j] = comb(j, i)
    p.setflags(write=False)
    return p


@cache
def l_vector(q: int) -> np.ndarray:
    """Coefficients l[0..q] of Lambda(x) = prod_{i=1..q} (1 + x/i), the BDF-q correction vector."""
    coeffs = np.array([1.0])
    for i in range(1, q + 1):
        coeffs = np.convolve(coeffs, [1.0, 1.0 / i])
    coeffs.setflags(write=False)
    return coeffs


@cache
def harmonic(q: int) -> float:
    """l[1] of order q: 1 + 1/2 + ... + 1/q."""
    return float(sum(1.0 / i for i in range(1, q + 1)))


@cache
def error_coefficient(q: int) -> float:
    """Milne's factor turning Delta = y_C - y_P into the local error of BDF-q."""
    return 1.0 / ((q + 1) * harmonic(q) + 1.0)


@cache
def lower_order_error_coefficient(q: int) -> float:
    """Factor turning z[q] into the local error the method of order q - 1 would make.

    LTE_{q-1} = h^q y^(q) / (q l1(q-1)) and z[q] = h^q y^(q) / q!, so the factor is
    (q - 1)! / l1(q - 1).
    """
    return factorial(q - 1) / harmonic(q - 1)


@cache
def higher_order_error_coefficient(q: int) -> float:
    """Factor turning Delta_n - Delta_{n-1} into the local error of order q + 1.

    Delta ~= (1 + 1/((q+1) l1(q))) h^(q+1) y^(q+1), so its backward difference
    estimates h^(q+2) y^(q+2) times the same factor, and LTE_{q+1} =
    h^(q+2) y^(q+2) / ((q+2) l1(q+1)).
    """
    return 1.0 / ((1.0 + 1.0 / ((q + 1) * harmonic(q))) * (q + 2) * harmonic(q + 1))


def predict(z: np.ndarray, q: int, out: np.ndarray | None = None) -> np.ndarray:
    """Taylor-shift the rows 0..q of the Nordsieck array one step ahead: P z.

    ``out``: an array of z's shape to hold the result in its rows 0..q (no new array).
    """
    if out is None:
        return pascal_matrix(q) @ z[: q + 1]
    return np.matmul(pascal_matrix(q), z[: q + 1], out=out[: q + 1])


#: ``kernels.rescale`` (the same products in a compiled loop), set by ``bdf`` when it
#: loads the compiled loops; None: numpy
compiled_rescale = None


def rescale(z: np.ndarray, q: int, ratio: float) -> None:
    """Change the step by the factor ``ratio`` in place: row j times ratio**j.

    The factors are the products ratio * ratio * ... (j of them) formed one after the
    other, and every row is multiplied by its own in one broadcast operation (the
    same products as row by row, bit for bit, in one numpy call instead of q).
    """
    if compiled_rescale is not None:
        compiled_rescale(z, q, ratio)
        return
    factors = [ratio]
    for _ in range(1, q):
        factors.append(factors[-1] * ratio)
    z[1 : q + 1] *= np.array(factors)[:, None]


@cache
def order_decrease_coefficients(q: int) -> np.ndarray:
    """Coefficients of x^2 (x + 1) ... (x + q - 2), degree q, for dropping order q to q - 1.

    Subtracting z[q] times this polynomial removes the degree-q term while the
    polynomial keeps its value and slope at s = 0 and its values at
    s = -1, ..., -(q - 2): the history a BDF of order q - 1 needs
    (the constant-step form of CVODE's cvAdjustBDF).
    """
    coeffs = np.array([0.0, 0.0, 1.0])  # x^2, ascending powers
    for j in range(1, q - 1):
        coeffs = np.convolve(coeffs, [float(j), 1.0])
    coeffs.setflags(write=False)
    return coeffs


def decrease_order(z: np.ndarray, q: int) -> None:
    """Turn a Nordsieck array of order q into one of order q - 1, in place."""
    c = order_decrease_coefficients(q)
    for j in range(2, q):
        z[j] -= c[j] * z[q]
    z[q] = 0.0


def increase_order(z: np.ndarray, q: int, delta: np.ndarray) -> None:
    """Add row q + 1 estimated from the last correction: z[q+1] = l_q Delta / (q + 1)."""
    z[q + 1] = l_vector(q)[q] * delta / (q + 1)


def interpolate(z: np.ndarray, q: int, h: float, s: float) -> tuple[np.ndarray, np.ndarray]:
    """Value and derivative of the Nordsieck polynomial at t_n + s h (s in [-1, 0] inside)."""
    y = z[q].copy()
    dy = q * z[q]
    for j in range(q - 1, -1, -1):
        y = y * s + z[j]
        if j >= 1:
            dy = dy * s + j * z[j]
    return y, dy / h


def interpolation_error(q: int, s: float) -> tuple[float, float]:
    """(a, b): the error of the corrected polynomial of order q at t_n + s h (s in
    [-1, 0]) is about a Delta in y and b Delta / h in y' (Delta = y_n - y_pred of the
    step, componentwise; a and b carry the sign of the error relative to Delta).

    The corrected polynomial interpolates y_n, y_(n-1), ..., y_(n-q) (constant steps:
    the correction l(s) Delta is zero at s = -1, ..., -q), so its error is
    h^(q+1) y^(q+1) w(s) / (q + 1)! with w(s) = s (s + 1) ... (s + q). The predictor is
    the previous polynomial extrapolated by one step, w(1) / (q + 1)! = 1: Delta ~=
    h^(q+1) y^(q+1) (y here is the smooth function through the computed points: their
    global error is part of it). So a = w(s) / (q + 1)!, b = w'(s) / (q + 1)!
    (tests/test_output_between_steps.py: the polynomial's error on y' = -y within 17 %
    of a Delta for q = 1 to 5).
    """
    w, dw = 1.0, 0.0
    for i in range(q + 1):  # w and w' factor by factor (product rule)
        dw = dw * (s + i) + w
        w = w * (s + i)
    c = 1.0 / factorial(q + 1)
    return c * w, c * dw


@cache
def largest_interpolation_error(q: int) -> float:
    """max over s in [-1, 0] of |a| (``interpolation_error``), on a grid of 1001 points."""
    return max(abs(interpolation_error(q, -k / 1000.0)[0]) for k in range(1001))
