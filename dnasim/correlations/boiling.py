"""Saturated flow boiling inside tubes: Chen (1966), with a stated dry-out limit."""

from __future__ import annotations

import numpy as np

from dnasim.correlations.heat_transfer import nusselt_dittus_boelter

#: default critical (dry-out) quality [-]: see chen_boiling
X_DRYOUT = 0.9


def lockhart_martinelli_xtt(x, rho_l, rho_v, mu_l, mu_v):
    """Turbulent-turbulent Lockhart-Martinelli parameter [-]:
    X_tt = ((1 - x)/x)^0.9 (rho_v/rho_l)^0.5 (mu_l/mu_v)^0.1."""
    return ((1.0 - x) / x) ** 0.9 * (rho_v / rho_l) ** 0.5 * (mu_l / mu_v) ** 0.1


def forster_zuber(dT_sat, dp_sat, rho_l, rho_v, mu_l, k_l, cp_l, h_lv, sigma):
    """Forster-Zuber nucleate boiling coefficient [W/(m2 K)] (AIChE J. 1, 531 (1955)):
    h = 0.00122 k^0.79 cp^0.45 rho_l^0.49 / (sigma^0.5 mu_l^0.29 h_lv^0.24 rho_v^0.24)
    dT_sat^0.24 dp_sat^0.75, with dT_sat = T_wall - T_sat [K] and dp_sat =
    p_sat(T_wall) - p [Pa] (both >= 0; clipped)."""
    dT = np.maximum(dT_sat, 0.0)
    dp = np.maximum(dp_sat, 0.0)
    return (
        0.00122
        * k_l**0.79
        * cp_l**0.45
        * rho_l**0.49
        / (sigma**0.5 * mu_l**0.29 * h_lv**0.24 * rho_v**0.24)
        * dT**0.24
        * dp**0.75
    )


def clapeyron_dp_sat(dT_sat, T_sat, p, h_lv, rho_l, rho_v):
    """p_sat(T_sat + dT_sat) - p [Pa], the vapour-pressure rise of a wall superheat
    dT_sat [K] (the dp_sat of :func:`forster_zuber`), from the Clausius-Clapeyron
    equation integrated with a constant slope parameter:

        p_sat(T) = p exp(a (T - T_sat) / T),   a = h_lv rho_l rho_v / ((rho_l - rho_v) p)

    which has Clapeyron's slope dp/dT = h_lv / (T (v_v - v_l)) at T = T_sat (exact for
    dT_sat -> 0) and the ideal-gas form ln p ~ -1/T beyond. T_sat [K], p [Pa], h_lv
    [J/kg], rho [kg/m3]. Measured against IF97's p_sat(T) (tests/test_correlations.py):
    within 1 % up to a superheat of 15 K and 2.5 % up to 30 K, from 1 to 150 bar (the
    nucleate term takes it to the power 0.75). Negative dT_sat gives the
    (negative) fall of the vapour pressure."""
    a = h_lv * rho_l * rho_v / ((rho_l - rho_v) * p)
    T = T_sat + dT_sat
    return p * np.expm1(a * dT_sat / T)


def chen_boiling(G, x, D, rho_l, rho_v, mu_l, mu_v, k_l, cp_l, h_lv, sigma, dT_sat, dp_sat,
                 x_dryout=X_DRYOUT, k_v=None, cp_v=None, nusselt=None):  # fmt: skip
    """Saturated flow boiling coefficient h [W/(m2 K)] by Chen (Ind. Eng. Chem. Process
    Des. Dev. 5, 322 (1966)), with the analytic F and S of Edelstein, Perez & Chen
    (AIChE J. 30, 840 (1984)):

        h = F h_l + S h_nb
        h_l = 0.023 Re_l^0.8 Pr_l^0.4 k_l / D,  Re_l = G (1 - x) D / mu_l
        F = (1 + X_tt^-0.5)^1.78
        S = 0.9622 - 0.5822 arctan(Re_l F^1.25 / 6.18e4)
        h_nb = Forster-Zuber (:func:`forster_zuber`) at the wall superheat

    Source range: water and organics in vertical tubes, 0.01 < x < 0.71, p 0.55 to
    35 bar, G up to about 4000 kg/(m2 s); about 12 % mean deviation.

    **Dry-out** (not in Chen's correlation): above the critical quality ``x_dryout``
    (default 0.9, a typical value for water at high mass flux; a natural-circulation
    evaporator stays below x = 0.3; give the value of a dry-out correlation or of the
    tube's data) the wall is dry: h falls linearly in x from h(x_dryout) to the
    vapour-only Dittus-Boelter value at x = 1, 0.023 Re_v^0.8 Pr_v^0.4 k_v / D with
    Re_v = G D / mu_v (k_v, cp_v required then; without them the post-dry-out value is
    NaN). At x <= 0 (subcooled, outside the correlation) x is taken as 0 (h = h_l +
    S h_nb with F = 1).

    G [kg/(m2 s)] (|G| used), x [-], D [m], rho [kg/m3], mu [Pa s], k [W/(m K)],
    cp [J/(kg K)], h_lv [J/kg], sigma [N/m], dT_sat [K], dp_sat [Pa].

    ``nusselt``: a function Nu(Re, Pr) replacing Dittus-Boelter in h_l and in the
    vapour-only value (default None: Chen's own Dittus-Boelter). A component that uses
    another single-phase correlation (Gnielinski) passes it, so that the two-phase
    coefficient joins its single-phase one at x = 0 (h = h_single + S h_nb) and at
    x = 1 (h = the vapour's): no jump of the coefficient where a volume's phase changes.
    """
    G = np.abs(np.asarray(G, dtype=float))
    x = np.asarray(x, dtype=float)
    xc = np.asarray(x_dryout, dtype=float)
    nu = nusselt_dittus_boelter if nusselt is None else nusselt

    def wet(xq):
        xq = np.clip(xq, 0.0, 1.0)
        Re_l = G * (1.0 - xq) * D / mu_l
        h_l = nu(Re_l, mu_l * cp_l / k_l) * k_l / D
        with np.errstate(divide="ignore"):
            xtt = lockhart_martinelli_xtt(np.maximum(xq, 1e-300), rho_l, rho_v, mu_l, mu_v)
        F = np.where(xq > 0.0, (1.0 + xtt**-0.5) ** 1.78, 1.0)
        S = 0.9622 - 0.5822 * np.arctan(Re_l * F**1.25 / 6.18e4)
        return F * h_l + S * forster_zuber(
            dT_sat, dp_sat, rho_l, rho_v, mu_l, k_l, cp_l, h_lv, sigma
        )

    h_wet = wet(np.minimum(x, xc))
    if k_v is None or cp_v is None:
        h_vap = np.nan
    else:
        h_vap = nu(G * D / mu_v, mu_v * cp_v / k_v) * k_v / D
    w = np.clip((x - xc) / np.maximum(1.0 - xc, 1e-12), 0.0, 1.0)
    return np.where(x > xc, (1.0 - w) * h_wet + w * h_vap, h_wet)
