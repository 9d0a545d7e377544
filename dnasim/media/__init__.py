"""Fluid media: properties from pressure p [Pa] and specific enthalpy h [J/kg].

::

    from dnasim.media import get_medium, PropertyError
    water = get_medium("Water")                   # IAPWS-IF97 (default for water)
    air = get_medium("Air")                       # constant-cp ideal gas
    air_real = get_medium("Air", backend="HEOS")  # CoolProp's real-gas air
    r134a = get_medium("R134a", backend="HEOS")   # any CoolProp fluid
    flue = get_medium("FlueGas")                  # N2/O2/CO2/H2O/Ar ideal mixture, NASA cp(T)
    gas = GasMixture("Exhaust", mole_fractions={"N2": 0.75, "O2": 0.14, "CO2": 0.05,
                                                "H2O": 0.05, "Ar": 0.01})
    st = water.state(1e5, 4.2e5)                  # -> FluidState (cached)
    sts = water.states(p_array, h_array)          # -> FluidStates (arrays, one call)
    water.saturation_enthalpies(p_array)          # -> (h_liq, h_vap) arrays
    water.h_px(p_array, x_array)                  # saturated mixture h
    st.T, st.rho, st.u, st.s, st.cp, st.quality, st.drho_dp_h, st.drho_dh_p
    water.h_pT(1e5, 350.0)                        # -> h [J/kg]
    water.transport(p, h)                         # -> {"mu", "k", "cp", "Pr"} arrays
    water.saturation_transport(p)                 # -> saturated mu_l, mu_v, k_l, ..., sigma

Every failure to evaluate a state is a :class:`PropertyError` (a
:class:`dnasim.core.errors.ResidualDomainError`) that names the fluid, p, h and the
property. CoolProp is imported only when a CoolProp medium is requested, numba
(for IF97 water) only when water is.
Modules: ``state`` (FluidState, FluidStates), ``errors`` (PropertyError),
``base`` (Medium and its cache), ``if97`` (water by IF97, on ``if97_kernel``,
the vectorised IAPWS-IF97 kernel, with ``if97_coefficients``), ``coolprop_medium``
(HEOS and tabular CoolProp backends), ``ideal_gas`` (IdealGas), ``gas_mixture``
(GasMixture: NASA-polynomial ideal-gas mixtures, flue gas), ``registry``
(get_medium and fluid names), ``water_transport`` (IAPWS viscosity, conductivity,
surface tension), ``gas_transport`` (dilute gases, Wilke and Mason-Saxena mixing).
"""

from dnasim.media.base import Medium
from dnasim.media.errors import PropertyError
from dnasim.media.gas_mixture import GasMixture
from dnasim.media.ideal_gas import IdealGas
from dnasim.media.registry import BACKENDS, canonical_fluid_name, get_medium
from dnasim.media.state import FluidState, FluidStates


def __getattr__(name: str):
    # CoolProp is imported only when a CoolProp medium is asked for (it takes seconds)
    if name == "CoolPropMedium":
        from dnasim.media.coolprop_medium import CoolPropMedium

        return CoolPropMedium
    # IF97 water imports numba (0.3 s CPU, and 0.3 s to load its compiled kernels):
    # only when water is asked for, so an air plant starts without it
    if name == "IF97Water":
        from dnasim.media.if97 import IF97Water

        return IF97Water
    raise AttributeError(f"module 'dnasim.media' has no attribute {name!r}")


__all__ = [
    "BACKENDS",
    "CoolPropMedium",
    "FluidState",
    "FluidStates",
    "GasMixture",
    "IF97Water",
    "IdealGas",
    "Medium",
    "PropertyError",
    "canonical_fluid_name",
    "get_medium",
]
