"""Radiation of hot flue gas (H2O and CO2): total emissivity and mean beam length."""

from __future__ import annotations

import numpy as np

#: Stefan-Boltzmann constant [W/(m2 K4)] (CODATA 2018)
SIGMA_SB = 5.670374419e-8
#: [Pa] one standard atmosphere
ATM = 101325.0

# Smith, Shen & Friedman, "Evaluation of coefficients for the weighted sum of gray gases
# model", J. Heat Transfer 104, 602 (1982), Table 2, H2O-CO2 mixtures at 1 atm total:
# per grey gas i, kappa_i [1/(atm m)] and b_i1..b_i4 of a_i(T) = sum_j b_ij T^(j-1),
# b_i1 x 1e-1, b_i2 x 1e-4 [1/K], b_i3 x 1e-7 [1/K2], b_i4 x 1e-11 [1/K3].
_SSF = {
    1.0: (  # p_H2O / p_CO2 = 1
        (0.4303, 5.150, -2.303, 0.9779, -1.494),
        (7.055, 0.7749, 3.399, -2.297, 3.770),
        (178.1, 1.907, -1.824, 0.5608, -0.5122),
    ),
    2.0: (  # p_H2O / p_CO2 = 2
        (0.4201, 6.508, -5.551, 3.029, -5.353),
        (6.516, -0.2504, 6.112, -3.882, 6.528),
        (131.9, 2.718, -3.118, 1.221, -1.612),
    ),
}
_SCALE = np.array([1e-1, 1e-4, 1e-7, 1e-11])


def _wsgg(T, pL_atm, table):
    eps = 0.0
    for kappa, *b in table:
        bb = np.array(b) * _SCALE
        a = bb[0] + T * (bb[1] + T * (bb[2] + T * bb[3]))
        eps = eps + a * (1.0 - np.exp(-kappa * pL_atm))
    return eps


def gas_emissivity(T, p_H2O, p_CO2, L):
    """Total emissivity [-] of an H2O-CO2 gas (non-luminous, no soot) by the weighted sum
    of grey gases with the coefficients of Smith, Shen & Friedman (1982) (three grey
    gases and a clear one):

        eps = sum_i a_i(T) (1 - exp(-kappa_i (p_H2O + p_CO2) L))

    T gas temperature [K], partial pressures [Pa], L path (mean beam) length [m]. The
    coefficients exist for p_H2O/p_CO2 = 1 (natural-gas and oil flames are near 2,
    coal near 1 or below) and 2; the emissivity is interpolated linearly in that ratio
    and held at the nearer set outside [1, 2] (a stated approximation). Source range:
    600 K <= T <= 2400 K, 0.001 <= (p_H2O + p_CO2) L <= 10 atm m, total pressure 1 atm;
    T is clipped to that range (the a_i polynomials are not meant beyond it). About 5
    to 10 % from the exponential wide-band model the fits were made to.
    """
    T = np.clip(np.asarray(T, dtype=float), 600.0, 2400.0)
    pw = np.asarray(p_H2O, dtype=float)
    pc = np.asarray(p_CO2, dtype=float)
    pL = (pw + pc) / ATM * np.asarray(L, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.clip(np.where(pc > 0.0, pw / pc, 2.0), 1.0, 2.0)
    e1 = _wsgg(T, pL, _SSF[1.0])
    e2 = _wsgg(T, pL, _SSF[2.0])
    return (2.0 - r) * e1 + (r - 1.0) * e2


def mean_beam_length(V, A):
    """Mean beam length [m] of a gas volume V [m3] radiating to its whole boundary A [m2]:
    L_m = 3.6 V / A (Hottel; Incropera et al. 6th ed., Table 13.4, "all other shapes";
    e.g. 0.95 D for a long cylinder, 0.65 D for a sphere is within 5 %)."""
    return 3.6 * np.asarray(V, dtype=float) / np.asarray(A, dtype=float)


def gas_wall_heat_flux(T_gas, T_wall, eps_gas, eps_wall=1.0):
    """Net radiative heat flux gas -> wall [W/m2], grey gas, gas absorptivity taken equal
    to its emissivity, and a grey wall by the effective-emissivity factor
    (eps_wall + 1)/2 (Hottel's approximation, VDI Heat Atlas K3; exact for a black
    wall): q = (eps_wall + 1)/2 sigma eps_gas (T_gas^4 - T_wall^4)."""
    Tg = np.asarray(T_gas, dtype=float)
    Tw = np.asarray(T_wall, dtype=float)
    return 0.5 * (np.asarray(eps_wall, dtype=float) + 1.0) * SIGMA_SB * eps_gas * (Tg**4 - Tw**4)
