"""Signal sources: what ``inputs = { measured = "X.q" }`` may name, its unit, and checks.

A signal input reads one scalar of the global vector. The source ``"X.q"`` is
resolved once, when the plant is compiled:

* ``X`` a component, ``q`` one of its signal outputs (``"pi.z"``, ``"sensor.T"``);
* ``X`` a component, ``q`` any of its variables, a vector element by index
  (``"valve.m"``, ``"pipe.m[3]"``, ``"drum.level"``, ``"pipe.h_v[0]"``);
* ``X`` a node, ``q`` its pressure ``p`` [Pa] or specific enthalpy ``h`` [J/kg]
  (both are unknowns of the DAE), or its temperature ``T`` [K]: the compiler then
  adds an ideal temperature sensor on the node (a probe named ``"X~T"``, variable
  ``"X~T.T_s"``, T = T(p, h) of the node's medium, no lag).

The unit of the source is the output's or the variable's declared unit (a signal
output declared with unit ``"*"`` has the unit its block derives from its linked
inputs' units, ``Component.signal_output_unit``: the first input's for a ``Gain`` or
``Limiter`` without a ``unit`` parameter, u1's times u2's for a ``Product``, u1's
over u2's for a ``Division``). A signal input with
a unit other than ``"*"`` takes only sources of the same dimension: a
temperature wired to a valve opening is an input error naming both ends.

This module has no state; ``dnasim.plant.plant``, ``dnasim.plant.plantfile`` and
``dnasim.compilation.compiler`` use it through :func:`resolve` and :func:`dimension_problem`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from dnasim.core.values import suggest as _suggest

__all__ = [
    "NODE_QUANTITIES",
    "Source",
    "resolve",
    "dimension_problem",
    "node_sensor_name",
    "split_ref",
]

#: node quantity -> (unit, doc)
NODE_QUANTITIES = {
    "p": ("Pa", "node pressure"),
    "h": ("J/kg", "specific enthalpy of the fluid flowing into the node"),
    "T": ("K", "node temperature T(p, h) of the node's medium"),
}

_ELEMENT = re.compile(r"^([A-Za-z_]\w*)\[(\d+)\]$")


@dataclass(frozen=True)
class Source:
    """A resolved signal source.

    kind: "output" (a signal output), "variable" (a component variable or vector
    element) or "node" (a node's p, h or T). ``variable``: the component's local
    variable name ("z", "m[3]") for "output" and "variable"; the quantity for a
    node. ``unit``: its SI unit ("*" when it follows an input not yet known)."""

    owner: str
    ref: str
    kind: str
    variable: str
    unit: str


def split_ref(ref) -> tuple[str, str] | None:
    """``"pipe.m[3]"`` -> ("pipe", "m[3]"); None when not of the form "name.quantity"."""
    if not isinstance(ref, str) or ref.count(".") != 1:
        return None
    a, b = ref.split(".")
    if not a or not b:
        return None
    return a, b


def node_sensor_name(node: str) -> str:
    """Name of the ideal sensor the compiler adds for a node temperature signal."""
    return f"{node}~T"


def _variable(comp, ref: str):
    """(local variable name, unit) of ``ref`` among ``comp.variables()``, or an error text."""
    m = _ELEMENT.match(ref)
    name, index = (m.group(1), int(m.group(2))) if m else (ref, None)
    variables = {v.name: v for v in comp.variables()}
    var = variables.get(name)
    if var is None:
        return None
    if var.size is None:
        if index is not None:
            return f"'{comp.name}.{name}' is a scalar variable; write '{comp.name}.{name}'"
        return (name, var.unit)
    if index is None:
        return (
            f"'{comp.name}.{name}' is a vector of {var.size} elements; name one element, "
            f"e.g. '{comp.name}.{name}[{var.size - 1}]'"
        )
    if index >= var.size:
        return (
            f"'{comp.name}.{name}[{index}]' is out of range: '{name}' has {var.size} elements "
            f"(0 .. {var.size - 1})"
        )
    return (f"{name}[{index}]", var.unit)


def resolve(owner: str, ref: str, component=None, is_node: bool = False) -> Source | str:
    """The source ``owner.ref``: a :class:`Source`, or a plain-words error text.

    ``component``: the component instance named ``owner`` (None when ``owner`` is
    not a component); ``is_node``: whether ``owner`` is a node of the plant."""
    if component is not None:
        for s in component.signal_outputs():
            if s.name == ref:
                return Source(owner, ref, "output", s.variable, str(s.unit or "1"))
        found = _variable(component, ref)
        if isinstance(found, tuple):
            return Source(owner, ref, "variable", found[0], found[1])
        if isinstance(found, str):
            return found
        outs = [s.name for s in component.signal_outputs()]
        names = [v.name + ("[i]" if v.size else "") for v in component.variables()]
        return (
            f"{type(component).__name__} '{owner}' has no signal output or variable '{ref}'"
            + _suggest(ref, outs + [v.name for v in component.variables()])
            + f" (signal outputs: {', '.join(outs) or 'none'}; variables: "
            + (", ".join(names) or "none")
            + ")"
        )
    if is_node:
        if ref in NODE_QUANTITIES:
            return Source(owner, ref, "node", ref, NODE_QUANTITIES[ref][0])
        return (
            f"node '{owner}' has no quantity '{ref}'{_suggest(ref, NODE_QUANTITIES)}; a node "
            "gives p [Pa], h [J/kg] and T [K]"
        )
    return None  # neither: the caller names what exists


def dimension_problem(
    src_label: str, src_unit: str, dst_label: str, dst_type: str, want: str, doc: str = ""
) -> str | None:
    """Why a source of unit ``src_unit`` cannot drive the input ``dst_label`` (its
    name) of ``dst_type`` ("Valve 'spray_valve'") expecting ``want`` (units of
    another dimension), or None. ``"*"`` on either side is not checked."""
    from dnasim.core.units import UnitError, parse_unit

    if want == "*" or src_unit == "*":
        return None
    try:
        uw, uh = parse_unit(want), parse_unit(src_unit)
    except UnitError:
        return None
    if uw.dims == uh.dims:
        return None
    return (
        f"dimension mismatch: '{src_label}' is a {uh.dimension} signal [{src_unit}], but the "
        f"input '{dst_label}' of {dst_type} expects {uw.dimension} [{want}]"
        + (f" ({doc})" if doc else "")
        + "; link a signal of that dimension, e.g. a controller output (or a Gain with a unit)"
    )
