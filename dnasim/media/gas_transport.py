"""Viscosity and thermal conductivity of dilute gases and their mixtures (air, flue gas).

Pure species (the dilute-gas, zero-density limit; the media of this package that use
it are ideal gases, Z = 1, at boiler flue-gas pressures about 1 bar):

* **N2, O2, CO2, Ar**: the NASA Glenn fits of the CEA program's transport data file
  ``trans.inp`` (McBride & Gordon; Svehla, "Transport coefficients for the NASA Lewis
  chemical equilibrium program", NASA TM-4647, 1995; data of Boushehri et al. 1987
  (N2, O2, CO2) and Bich et al. 1990 (Ar))::

      ln(mu / 1e-7 Pa s)      = A ln T + B / T + C / T^2 + D       (mu in micropoise)
      ln(k / 1e-4 W/(m K))    = A ln T + B / T + C / T^2 + D       (k in uW/(cm K))

  in two ranges, 200 K..1000 K and 1000 K..5000 K (transcribed in :data:`CEA_FITS`).
  The fits of the two ranges differ at 1000 K by at most 1e-7 relative (printed
  digits; :func:`range_jumps`), which is left as it is. Above 5000 K (the gas
  mixtures reach 6000 K) the high range is extrapolated.
* **H2O**: the dilute-gas terms of the IAPWS formulations, mu0(T) of R12-08 eq. (11)
  and lambda0(T) of R15-11 eq. (16) (the same numbers as
  :mod:`dnasim.media.water_transport` at rho = 0), valid to 1173.15 K and
  extrapolated beyond. (CEA's own H2O fit starts at 373.2 K and lies 3.6 % above
  lambda0 there; from 500 K to 3000 K the two agree within 1 % in mu and 4 % in k.)

Mixtures (mole fractions x_i, molar masses M_i):

* viscosity by **Wilke's rule** (Wilke, J. Chem. Phys. 18, 517 (1950); Poling,
  Prausnitz & O'Connell, "The Properties of Gases and Liquids", 5th ed., eq. 9-5.13)::

      mu = sum_i x_i mu_i / sum_j x_j Phi_ij
      Phi_ij = [1 + (mu_i / mu_j)^(1/2) (M_j / M_i)^(1/4)]^2 / [8 (1 + M_i / M_j)]^(1/2)

* conductivity by the **Wassiljewa equation with the Mason-Saxena coefficients**
  (Mason & Saxena, Phys. Fluids 1, 361 (1958); Poling et al. eq. 10-6.1 and 10-6.2,
  with epsilon = 1.0 as recommended there)::

      k = sum_i x_i k_i / sum_j x_j A_ij,     A_ij = Phi_ij (the viscosity's)

Checked against published tables (air, Incropera's Table A.4) and CoolProp's
reference correlations (tests/test_gas_transport.py): air within 1.5 % from 250 K to
1000 K, pure species within 1 to 3 %.
"""

from __future__ import annotations

import math

import numpy as np

#: CEA (trans.inp) fits: species -> (T_switch [K], mu_low, mu_high, k_low, k_high),
#: each (A, B, C, D) of the module docstring's form (mu in micropoise, k in uW/(cm K)).
CEA_FITS = {
    "N2": (
        1000.0,
        (0.62526577, -31.779652, -1640.7983, 1.7454992),
        (0.87395209, 561.52222, -173948.09, -0.39335958),
        (0.85439436, 105.73224, -12347.848, 0.47793128),
        (0.88407146, 133.57293, -11429.640, 0.24417019),
    ),
    "O2": (
        1000.0,
        (0.60916180, -52.244847, -599.74009, 2.0410801),
        (0.72216486, 175.50839, -57974.816, 1.0901044),
        (0.77229167, 6.8463210, -5893.3377, 1.2210365),
        (0.90917351, 291.24182, -79650.171, 0.064851631),
    ),
    "CO2": (
        1000.0,
        (0.51137258, -229.51321, 13710.678, 2.7075538),
        (0.63978285, -42.637076, -15522.605, 1.6628843),
        (0.48056568, -507.86720, 35088.811, 3.6747794),
        (0.69857277, -118.30477, -50688.859, 1.8650551),
    ),
    "Ar": (
        1000.0,
        (0.61205763, -67.714354, 190.40660, 2.1588272),
        (0.69357334, 70.953943, -28386.007, 1.4856447),
        (0.60968928, -70.892249, 584.20624, 1.9337152),
        (0.69075463, 62.676058, -25667.413, 1.2664189),
    ),
}

# IAPWS dilute-gas terms for H2O (R12-08 Table 1, R15-11 Table 1; T_c = 647.096 K)
_T_C = 647.096
_MU_H = (1.67752, 2.20462, 0.6366564, -0.241605)
_K_L = (2.443221e-3, 1.323095e-2, 6.770357e-3, -3.454586e-3, 4.096266e-4)

#: molar masses [kg/mol] (those of dnasim.media.gas_mixture.SPECIES)
MOLAR_MASS = {"N2": 28.0134e-3, "O2": 31.9988e-3, "CO2": 44.0095e-3, "H2O": 18.01528e-3,
              "Ar": 39.948e-3}  # fmt: skip

SPECIES = ("N2", "O2", "CO2", "H2O", "Ar")


def _cea(c, lnT, T):
    return np.exp(c[0] * lnT + c[1] / T + c[2] / (T * T) + c[3])


def species_mu_k(species: str, T):
    """(mu [Pa s], k [W/(m K)]) of one species as a dilute gas at T [K] (arrays)."""
    T = np.asarray(T, dtype=float)
    if species == "H2O":
        Tr = T / _T_C
        s_mu = _MU_H[0] + (_MU_H[1] + (_MU_H[2] + _MU_H[3] / Tr) / Tr) / Tr
        s_k = _K_L[0] + (_K_L[1] + (_K_L[2] + (_K_L[3] + _K_L[4] / Tr) / Tr) / Tr) / Tr
        root = np.sqrt(Tr)
        return 1e-4 * root / s_mu, 1e-3 * root / s_k
    if species not in CEA_FITS:
        raise KeyError(f"no transport data for species {species!r}; known: {', '.join(SPECIES)}")
    Ts, mu_lo, mu_hi, k_lo, k_hi = CEA_FITS[species]
    lnT = np.log(T)
    hi = T >= Ts
    mu = np.where(hi, _cea(mu_hi, lnT, T), _cea(mu_lo, lnT, T))
    k = np.where(hi, _cea(k_hi, lnT, T), _cea(k_lo, lnT, T))
    return 1e-7 * mu, 1e-4 * k


def range_jumps() -> dict[str, tuple[float, float]]:
    """{species: (relative jump of mu, of k)} of the CEA fits at their 1000 K switch."""
    out = {}
    for s, (Ts, mu_lo, mu_hi, k_lo, k_hi) in CEA_FITS.items():
        lnT = math.log(Ts)
        out[s] = (
            float(_cea(mu_hi, lnT, Ts) / _cea(mu_lo, lnT, Ts) - 1.0),
            float(_cea(k_hi, lnT, Ts) / _cea(k_lo, lnT, Ts) - 1.0),
        )
    return out


class MixtureTransport:
    """mu(T), k(T) of a gas mixture of fixed mole fractions (Wilke, Mason-Saxena).

    Parameters
    ----------
    mole_fractions : dict
        {species: x_i [-]} over :data:`SPECIES` (zero fractions may be left out; they
        are renormalised to sum 1).
    """

    def __init__(self, mole_fractions: dict[str, float]) -> None:
        items = [(s, float(x)) for s, x in mole_fractions.items() if float(x) > 0.0]
        for s, _ in items:
            if s not in MOLAR_MASS:
                raise KeyError(f"no transport data for species {s!r}; known: {', '.join(SPECIES)}")
        tot = math.fsum(x for _, x in items)
        self.species = tuple(s for s, _ in items)
        self.x = np.array([x / tot for _, x in items])
        M = np.array([MOLAR_MASS[s] for s in self.species])
        # the parts of Phi_ij that do not depend on T: (M_j/M_i)^(1/4), [8 (1 + M_i/M_j)]^(-1/2)
        self._m14 = ((M[None, :] / M[:, None]) ** 0.25)[:, :, None]
        self._den = (1.0 / np.sqrt(8.0 * (1.0 + M[:, None] / M[None, :])))[:, :, None]
        # plain floats for :meth:`scalar`
        self._x_l = self.x.tolist()
        self._m14_l = self._m14[:, :, 0].tolist()
        self._den_l = self._den[:, :, 0].tolist()

    def scalar(self, T: float) -> tuple[float, float]:
        """(mu [Pa s], k [W/(m K)]) at one T [K]: the same formulas in plain floats
        (faster than the array code for a few points)."""
        lnT = math.log(T)
        mus = []
        ks = []
        for s in self.species:
            if s == "H2O":
                Tr = T / _T_C
                s_mu = _MU_H[0] + (_MU_H[1] + (_MU_H[2] + _MU_H[3] / Tr) / Tr) / Tr
                s_k = _K_L[0] + (_K_L[1] + (_K_L[2] + (_K_L[3] + _K_L[4] / Tr) / Tr) / Tr) / Tr
                r = math.sqrt(Tr)
                mus.append(1e-4 * r / s_mu)
                ks.append(1e-3 * r / s_k)
                continue
            Ts, mu_lo, mu_hi, k_lo, k_hi = CEA_FITS[s]
            cm, ck = (mu_hi, k_hi) if T >= Ts else (mu_lo, k_lo)
            mus.append(1e-7 * math.exp(cm[0] * lnT + cm[1] / T + cm[2] / (T * T) + cm[3]))
            ks.append(1e-4 * math.exp(ck[0] * lnT + ck[1] / T + ck[2] / (T * T) + ck[3]))
        n = len(mus)
        if n == 1:
            return mus[0], ks[0]
        x = self._x_l
        mu = k = 0.0
        for i in range(n):
            D = 0.0
            for j in range(n):
                phi = (1.0 + math.sqrt(mus[i] / mus[j]) * self._m14_l[i][j]) ** 2 * self._den_l[i][
                    j
                ]
                D += x[j] * phi
            mu += x[i] * mus[i] / D
            k += x[i] * ks[i] / D
        return mu, k

    def __call__(self, T):
        """(mu [Pa s], k [W/(m K)]) arrays of the shape of T [K]."""
        T = np.asarray(T, dtype=float)
        shape = T.shape
        Tf = T.reshape(1, -1)
        mus = []
        ks = []
        for s in self.species:
            m, k = species_mu_k(s, Tf[0])
            mus.append(m)
            ks.append(k)
        mu_i = np.array(mus)
        k_i = np.array(ks)
        if len(self.species) == 1:
            return mu_i[0].reshape(shape), k_i[0].reshape(shape)
        r = np.sqrt(mu_i[:, None, :] / mu_i[None, :, :])
        phi = (1.0 + r * self._m14) ** 2 * self._den
        D = np.einsum("j,ijn->in", self.x, phi)
        xi = self.x[:, None]
        mu = np.sum(xi * mu_i / D, axis=0)
        k = np.sum(xi * k_i / D, axis=0)
        return mu.reshape(shape), k.reshape(shape)
