"""`get_medium`: fluid names and backends to shared :class:`Medium` instances."""

from __future__ import annotations

import difflib
import re

from dnasim.core.errors import PlantError
from dnasim.media.base import BACKEND_ERRORS, Medium

#: Backends accepted by :func:`get_medium` (case-insensitive).
BACKENDS = ("IF97", "IF97-TABLES", "HEOS", "BICUBIC&HEOS", "TTSE&HEOS", "IdealGas", "NASA7")
_BACKEND_KEYS = {b.lower(): b for b in BACKENDS}
_BACKEND_KEYS.update({"ideal": "IdealGas", "ideal_gas": "IdealGas", "ideal-gas": "IdealGas"})
_BACKEND_KEYS.update({"if97_tables": "IF97-TABLES", "if97tables": "IF97-TABLES"})

_INSTANCES: dict[tuple[str, str], Medium] = {}
_NAMES: dict[str, str] | None = None  # normalised spelling -> canonical CoolProp name
_FLUIDS: list[str] = []


#: spellings answered without importing CoolProp (CoolProp's own aliases of these fluids)
_COMMON_NAMES = {"water": "Water", "h2o": "Water", "r718": "Water", "air": "Air"}


def _norm(name: str) -> str:
    return re.sub(r"[\s\-_]", "", name).lower()


def _name_table() -> dict[str, str]:
    """Normalised spellings (names and aliases) -> canonical CoolProp names, built once."""
    global _NAMES
    if _NAMES is None:
        import CoolProp.CoolProp as CP  # lazily: importing CoolProp takes seconds

        fluids = [f for f in CP.get_global_param_string("FluidsList").split(",") if f]
        table: dict[str, str] = {}
        ambiguous: set[str] = set()
        for f in fluids:
            try:
                aliases = CP.get_fluid_param_string(f, "aliases").split(",")
            except BACKEND_ERRORS:
                aliases = []
            for a in aliases:
                k = _norm(a)
                if not k:
                    continue
                if k in table and table[k] != f:
                    ambiguous.add(k)
                table[k] = f
        for k in ambiguous:
            del table[k]
        for f in fluids:  # canonical names win over any alias
            table[_norm(f)] = f
        _FLUIDS[:] = sorted(fluids)
        _NAMES = table
    return _NAMES


def canonical_fluid_name(fluid: str) -> str:
    """Return CoolProp's canonical name for ``fluid`` (case, '-', '_' and aliases ignored).

    ``"water"``, ``"H2O"``, ``"R718"`` -> ``"Water"``; ``"r-134a"`` -> ``"R134a"``;
    ``"co2"`` -> ``"CarbonDioxide"``.

    Raises
    ------
    dnasim.core.errors.PlantError
        For an unknown name, with close matches and the way to list all names.
    """
    key = _norm(fluid)
    common = _COMMON_NAMES.get(key)
    if common is not None:
        return common
    table = _name_table()
    if key in table:
        return table[key]
    close = difflib.get_close_matches(key, list(table), n=5, cutoff=0.6)
    suggestions = []
    for k in close:
        if table[k] not in suggestions:
            suggestions.append(table[k])
    hint = f" Did you mean {', '.join(repr(s) for s in suggestions)}?" if suggestions else ""
    raise PlantError(
        f"unknown fluid {fluid!r}.{hint} Fluids are spelled as CoolProp names or aliases "
        "(case, '-' and '_' do not matter), e.g. 'Water', 'Air', 'R134a', 'Nitrogen', "
        "'CarbonDioxide'; the full list is "
        "CoolProp.CoolProp.get_global_param_string('FluidsList'). A backend may be given as a "
        "prefix, e.g. 'IF97::Water', 'HEOS::Air', 'BICUBIC&HEOS::Water'."
    )


def _canonical_backend(backend: str) -> str:
    b = _BACKEND_KEYS.get(backend.strip().lower())
    if b is None:
        raise PlantError(f"unknown fluid backend {backend!r}; choose one of {', '.join(BACKENDS)}")
    return b


def get_medium(fluid: str, backend: str | None = None) -> Medium:
    """Return the shared medium for ``fluid`` and ``backend``.

    One instance exists per (canonical fluid, backend), so every component
    using e.g. water shares one property cache.

    Parameters
    ----------
    fluid : str
        A CoolProp fluid name or alias, case-insensitive (``"Water"``,
        ``"water"``, ``"H2O"``, ``"R134a"``, ``"Air"``, ...), optionally with a
        CoolProp-style backend prefix (``"IF97::Water"``, ``"HEOS::Water"``,
        ``"BICUBIC&HEOS::Water"``), or an ideal-gas mixture of N2, O2, CO2, H2O, Ar:
        ``"FlueGas"`` (natural-gas flue gas, :data:`~dnasim.media.gas_mixture.
        FLUE_GAS_DEFAULT`) or ``"FlueGas[N2=0.72,CO2=0.13,H2O=0.11,O2=0.03,Ar=0.01]"``
        (mole fractions), both :class:`~dnasim.media.GasMixture` with backend ``"NASA7"``.
    backend : str, optional
        ``"IF97"`` (water only), ``"IF97-TABLES"`` (water only: bicubic spline tables
        of IF97, :class:`~dnasim.media.if97_tables.TabulatedWater`), ``"HEOS"``,
        ``"BICUBIC&HEOS"``, ``"TTSE&HEOS"``
        ``"IdealGas"`` (air only) or ``"NASA7"`` (gas mixtures only). Defaults:
        ``"IF97"`` for water,
        ``"IdealGas"`` for air (constant-cp ideal gas,
        :class:`~dnasim.media.IdealGas` with R = 287.05 J/(kg K),
        cp = 1006 J/(kg K)), ``"HEOS"`` for every other fluid.

    Returns
    -------
    Medium
        :class:`~dnasim.media.if97.IF97Water`, :class:`~dnasim.media.IdealGas`
        or :class:`~dnasim.media.coolprop_medium.CoolPropMedium`.

    Raises
    ------
    dnasim.core.errors.PlantError
        Unknown fluid name (with "did you mean" suggestions), unknown backend,
        conflicting backends, a backend that does not cover the fluid.
    """
    if not isinstance(fluid, str):
        raise PlantError(f"fluid name must be a string, got {fluid!r}")
    name = fluid.strip()
    if "::" in name:
        prefix, name = name.split("::", 1)
        prefix_b = _canonical_backend(prefix)
        if backend is not None and _canonical_backend(backend) != prefix_b:
            raise PlantError(
                f"fluid {fluid!r} names backend {prefix_b!r} but backend={backend!r} was given"
            )
        backend = prefix_b
    from dnasim.media.gas_mixture import gas_mixture_from_name, is_gas_mixture_name

    if is_gas_mixture_name(name):  # "FlueGas", "FlueGas[N2=0.72,...]": NASA7 mixtures
        if backend is not None and _canonical_backend(backend) != "NASA7":
            raise PlantError(
                f"fluid {fluid!r} is an ideal-gas mixture (backend 'NASA7'), not {backend!r}"
            )
        mix = gas_mixture_from_name(name)
        medium = _INSTANCES.get((mix.name, "NASA7"))
        if medium is None:
            medium = _INSTANCES[(mix.name, "NASA7")] = mix
            medium.registry_call = (get_medium, (name, "NASA7"))
        return medium
    canon = canonical_fluid_name(name)
    if backend is None:
        b = {"Water": "IF97", "Air": "IdealGas"}.get(canon, "HEOS")
    else:
        b = _canonical_backend(backend)
    key = (canon, b)
    medium = _INSTANCES.get(key)
    if medium is None:
        medium = _create(canon, b)
        medium.registry_call = (get_medium, key)
        _INSTANCES[key] = medium
    return medium


def _create(canon: str, backend: str) -> Medium:
    if backend == "NASA7":
        raise PlantError(
            f"backend 'NASA7' covers only the ideal-gas mixtures 'FlueGas' and "
            f"'FlueGas[N2=...,O2=...,CO2=...,H2O=...,Ar=...]' (mole fractions), not {canon!r}"
        )
    if backend == "IF97":
        if canon != "Water":
            raise PlantError(f"backend 'IF97' covers only water, not {canon!r}; use backend='HEOS'")
        from dnasim.media.if97 import IF97Water

        return IF97Water()
    if backend == "IF97-TABLES":
        if canon != "Water":
            raise PlantError(
                f"backend 'IF97-TABLES' (tables of IAPWS-IF97) covers only water, not {canon!r}"
            )
        from dnasim.media.if97_tables import TabulatedWater

        return TabulatedWater()
    if backend == "IdealGas":
        if canon != "Air":
            raise PlantError(
                f"backend 'IdealGas' is predefined only for air, not {canon!r}; construct "
                "dnasim.media.IdealGas(name, R=..., cp=...) directly, or use backend='HEOS'"
            )
        from dnasim.media.ideal_gas import IdealGas

        return IdealGas("Air")
    from dnasim.media.coolprop_medium import CoolPropMedium

    try:
        return CoolPropMedium(canon, backend)
    except BACKEND_ERRORS as exc:
        raise PlantError(
            f"CoolProp cannot set up fluid {canon!r} with backend {backend!r}: {exc}"
        ) from exc
