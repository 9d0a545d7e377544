"""The one error type the media layer raises for a state it cannot evaluate."""

from __future__ import annotations

import math

from dnasim.core.errors import ResidualDomainError


def _fmt_p(p: float) -> str:
    """``p`` [Pa] as "1.000000e+05 Pa (1.000000 bar)"."""
    try:
        return f"p = {p:.9g} Pa ({p / 1e5:.9g} bar)"
    except (TypeError, ValueError):
        return f"p = {p!r}"


def _fmt_h(h: float) -> str:
    """``h`` [J/kg] as "4.19e+05 J/kg (419 kJ/kg)"."""
    try:
        return f"h = {h:.9g} J/kg ({h / 1e3:.9g} kJ/kg)"
    except (TypeError, ValueError):
        return f"h = {h!r}"


class PropertyError(ResidualDomainError):
    """A fluid property could not be evaluated at a state.

    Every failure of the media layer is turned into this one type: a negative,
    zero, NaN or infinite input, a state outside a backend's range, a failed
    flash inside CoolProp (which raises ``ValueError``, ``IndexError`` or
    ``RuntimeError`` depending on the backend), a NaN output. It subclasses
    :class:`dnasim.core.errors.ResidualDomainError`, so when raised inside a residual
    evaluation the solver treats it as a failed Newton iteration and cuts the
    step.

    Attributes
    ----------
    fluid : str
        Medium description, e.g. ``"Water (IF97)"``.
    p : float
        Pressure [Pa] of the failed state.
    h : float
        Specific enthalpy [J/kg] of the failed state (``nan`` when the failing
        call was given a temperature instead, see ``T``).
    prop : str
        What was being computed: ``"state"`` (the full (p, h) state), ``"h_pT"``,
        ``"drho_dp_h"``, ...
    reason : str
        The underlying message (CoolProp's own text, or ours).
    T : float or None
        Temperature [K] for failures of ``h_pT``; ``None`` otherwise.
    """

    def __init__(
        self,
        fluid: str,
        p: float,
        h: float,
        prop: str,
        reason: str = "",
        *,
        T: float | None = None,
    ) -> None:
        self.fluid = fluid
        self.p = p
        self.h = h
        self.prop = prop
        self.reason = reason
        self.T = T
        where = _fmt_p(p)
        if T is not None:
            try:
                where += f", T = {T:.9g} K ({T - 273.15:.9g} degC)"
            except (TypeError, ValueError):
                where += f", T = {T!r}"
        if T is None or not (isinstance(h, float) and math.isnan(h)):
            where += ", " + _fmt_h(h)
        msg = f"{fluid}: cannot evaluate {prop} at {where}"
        if reason:
            msg += f": {reason}"
        super().__init__(msg)

    def __reduce__(self):  # keep the attributes through pickling (multiprocessing)
        return (
            _rebuild_property_error,
            (self.fluid, self.p, self.h, self.prop, self.reason, self.T),
        )


def _rebuild_property_error(fluid, p, h, prop, reason, T):
    return PropertyError(fluid, p, h, prop, reason, T=T)
