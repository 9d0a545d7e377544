"""Film condensation inside tubes: Shah (1979)."""

from __future__ import annotations

import numpy as np


def shah_condensation(G, x, D, mu_l, k_l, cp_l, p_reduced):
    """Condensation coefficient h [W/(m2 K)] inside tubes by Shah (Int. J. Heat Mass
    Transfer 22, 547 (1979)):

        h = h_lo [(1 - x)^0.8 + 3.8 x^0.76 (1 - x)^0.04 / p_r^0.38]
        h_lo = 0.023 Re_lo^0.8 Pr_l^0.4 k_l / D,   Re_lo = G D / mu_l (all flow as liquid)

    Source range: D 7 to 40 mm, p_r = p / p_c 0.002 to 0.44, G 11 to 211 kg/(m2 s),
    Re_lo >= 350, 0 < x < 1, Pr_l 1 to 13 (water, refrigerants, organics; horizontal,
    vertical and inclined tubes); mean deviation about 15 %. Outside it the formula is
    evaluated as written (x clipped to [0, 1]; at x = 0 it is the liquid-only
    coefficient). G [kg/(m2 s)] (|G| used), D [m], mu_l [Pa s], k_l [W/(m K)],
    cp_l [J/(kg K)], p_reduced [-].
    """
    G = np.abs(np.asarray(G, dtype=float))
    x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
    Re = G * D / mu_l
    h_lo = 0.023 * Re**0.8 * (mu_l * cp_l / k_l) ** 0.4 * k_l / D
    return h_lo * ((1.0 - x) ** 0.8 + 3.8 * x**0.76 * (1.0 - x) ** 0.04 / p_reduced**0.38)
