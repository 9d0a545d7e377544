"""Film condensation: inside tubes by Shah (1979); outside horizontal tubes and tube
banks by Nusselt (1916) with Kern's row correction."""

from __future__ import annotations

import numpy as np


def shah_condensation(G, x, D, mu_l, k_l, cp_l, p_reduced, nusselt=None):
    """Condensation coefficient h [W/(m2 K)] inside tubes by Shah (Int. J. Heat Mass
    Transfer 22, 547 (1979)):

        h = h_lo [(1 - x)^0.8 + 3.8 x^0.76 (1 - x)^0.04 / p_r^0.38]
        h_lo = 0.023 Re_lo^0.8 Pr_l^0.4 k_l / D,   Re_lo = G D / mu_l (all flow as liquid)

    Source range: D 7 to 40 mm, p_r = p / p_c 0.002 to 0.44, G 11 to 211 kg/(m2 s),
    Re_lo >= 350, 0 < x < 1, Pr_l 1 to 13 (water, refrigerants, organics; horizontal,
    vertical and inclined tubes); mean deviation about 15 %. Outside it the formula is
    evaluated as written (x clipped to [0, 1]; at x = 0 it is the liquid-only
    coefficient). G [kg/(m2 s)] (|G| used), D [m], mu_l [Pa s], k_l [W/(m K)],
    cp_l [J/(kg K)], p_reduced [-]. ``nusselt``: a function Nu(Re, Pr) for h_lo instead
    of Shah's Dittus-Boelter (a component's single-phase correlation, so that the
    coefficient joins it at x = 0).
    """
    G = np.abs(np.asarray(G, dtype=float))
    x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
    Re = G * D / mu_l
    Pr = mu_l * cp_l / k_l
    if nusselt is None:
        h_lo = 0.023 * Re**0.8 * Pr**0.4 * k_l / D
    else:
        h_lo = nusselt(Re, Pr) * k_l / D
    return h_lo * ((1.0 - x) ** 0.8 + 3.8 * x**0.76 * (1.0 - x) ** 0.04 / p_reduced**0.38)


#: [m/s2] standard gravity
G_N = 9.80665


def nusselt_horizontal_tube(D, dT, rho_l, rho_v, mu_l, k_l, cp_l, h_lv, n_rows=1,
                            row_exponent=-1.0 / 6.0):  # fmt: skip
    """Mean coefficient h [W/(m2 K)] of laminar film condensation on the outside of
    horizontal tubes, Nusselt's theory (Z. VDI 60, 541 (1916)) as in Incropera et al.,
    "Fundamentals of Heat and Mass Transfer", 6th ed., eq. 10.41, with Rohsenow's latent
    heat corrected for the film's subcooling (eq. 10.26 there):

        h_1 = 0.729 [g rho_l (rho_l - rho_v) k_l^3 h'_lv / (mu_l dT D)]^(1/4)
        h'_lv = h_lv + 0.68 cp_l dT

    and for a vertical tier of N tubes (a bank of N rows, condensate draining from row
    to row) h = h_1 N^e: Nusselt's theory gives e = -1/4, which underestimates measured
    banks; Kern's e = -1/6 (D. Q. Kern, "Process Heat Transfer" 1950; VDI Heat Atlas
    J1) is the default. dT = T_sat - T_wall [K] (> 0; clipped at 1e-3 K, the
    coefficient grows as dT^(-1/4) towards it); D outer diameter [m]; liquid properties
    (rho_l, mu_l, k_l, cp_l) at the film temperature, rho_v of the vapour [kg/m3], h_lv
    [J/kg]. Laminar film, quiescent vapour (no vapour shear), no non-condensable gas:
    a clean condenser's upper bound; a design with air in-leakage or fouling has less.
    """
    dT = np.maximum(np.asarray(dT, dtype=float), 1e-3)
    h_mod = h_lv + 0.68 * cp_l * dT
    h1 = 0.729 * (G_N * rho_l * (rho_l - rho_v) * k_l**3 * h_mod / (mu_l * dT * D)) ** 0.25
    return h1 * np.asarray(n_rows, dtype=float) ** row_exponent
