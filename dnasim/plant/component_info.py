"""What a component type offers, read from its class: fluid ports, signal inputs and
outputs, parameters, declared equations (``component_info``: ``dnasim components``,
plant-file checks and docs/components.md)."""

from __future__ import annotations

import inspect
from collections.abc import Mapping

from dnasim.core.values import (
    param_kind,
    param_unit,
)


def _registry() -> dict[str, type]:
    from dnasim.plant.plugins import registry

    return registry()


def _names(obj) -> list[str]:
    """Port names from a list/tuple/dict of names or port objects."""
    if obj is None:
        return []
    if isinstance(obj, Mapping):
        return [str(k) for k in obj]
    out = []
    for p in obj:
        out.append(p if isinstance(p, str) else str(getattr(p, "name", p)))
    return out


def _first_attr(cls, names):
    for n in names:
        v = getattr(cls, n, None)
        if v is not None and not callable(v) or isinstance(v, list | tuple | dict):
            return v
    return None


def fluid_ports(cls) -> list[str]:
    return _names(_first_attr(cls, ("FLUID_PORTS", "PORTS", "fluid_ports", "ports")))


def signal_inputs(cls) -> list[str]:
    return _names(
        _first_attr(cls, ("SIGNAL_INPUTS", "INPUTS", "signal_inputs", "inputs", "SIGNALS_IN"))
    )


def signal_outputs(cls) -> list[str]:
    return _names(
        _first_attr(cls, ("SIGNAL_OUTPUTS", "OUTPUTS", "signal_outputs", "outputs", "SIGNALS_OUT"))
    )


def params_of(cls) -> list:
    return list(getattr(cls, "PARAMS", ()) or ())


def _is_required(p) -> bool:
    d = getattr(p, "default", None)
    try:
        from dnasim.library import REQUIRED
    except ImportError:
        REQUIRED = None  # noqa: N806
    if REQUIRED is not None and d is REQUIRED:
        return True
    return type(d).__name__.upper().startswith("REQUIRED") or repr(d).upper() == "REQUIRED"


def _port_info(ports) -> list[dict]:
    out = []
    for p in ports or ():
        if isinstance(p, str):
            out.append({"name": p, "role": "", "unit": "", "doc": ""})
        else:
            out.append(
                {
                    "name": str(getattr(p, "name", p)),
                    "role": str(getattr(p, "role", "") or ""),
                    "unit": str(getattr(p, "unit", "") or ""),
                    "doc": str(getattr(p, "doc", "") or ""),
                }
            )
    return out


def _declared_equations(cls, params) -> list[str]:
    """The equations a component declares (``Component.equations()`` of an example
    instance: required numbers set to 1), one line each, "name[i]" for a vector
    equation: "name [unit]: doc". Empty when no example can be built."""
    required = {p["name"]: 1.0 for p in params if p["required"] and p["kind"] == "number"}
    try:
        eqs = cls("example", **required).equations()
    except Exception:
        return []
    out = []
    for e in eqs:
        name = e.name if getattr(e, "size", None) is None else f"{e.name}[i]"
        unit = f" [{e.unit}]" if e.unit else ""
        out.append(f"{name}{unit}: {e.doc}".rstrip(": ") if e.doc else f"{name}{unit}")
    return out


def component_info(cls) -> dict:
    """Ports, parameters (unit, default, range, doc) and equations of a component class.

    The equations are those its docstring lists (the component library documents
    them there); ``EQUATIONS`` on the class, if present, is used as well."""
    params = []
    for p in params_of(cls):
        params.append(
            {
                "name": p.name,
                "unit": param_unit(p),
                "required": _is_required(p),
                "default": None if _is_required(p) else getattr(p, "default", None),
                "min": getattr(p, "min", None),
                "max": getattr(p, "max", None),
                "doc": getattr(p, "doc", "") or "",
                "time_function": bool(getattr(p, "time_function", False)),
                "kind": param_kind(p),
                "choices": getattr(p, "choices", None),
            }
        )
    eqs = getattr(cls, "EQUATIONS", None)
    if eqs is None:
        eqs = []
    elif isinstance(eqs, str):
        eqs = [e for e in eqs.strip().splitlines() if e.strip()]
    if not eqs:
        eqs = _declared_equations(cls, params)
    fports, sins = fluid_ports(cls), signal_inputs(cls)
    if not any(p["required"] for p in params):
        # ports may depend on parameters (a Mixer's inlets): list the defaults' ports
        try:
            inst = cls("example")
            fports, sins = _names(inst.fluid_ports()), _names(inst.signal_inputs())
        except Exception:
            pass
    return {
        "type": cls.__name__,
        "doc": inspect.cleandoc(cls.__doc__ or ""),
        "fluid_ports": fports,
        "signal_inputs": sins,
        "signal_outputs": signal_outputs(cls),
        "fluid_port_info": _port_info(getattr(cls, "FLUID_PORTS", ())),
        "signal_input_info": _port_info(getattr(cls, "SIGNAL_INPUTS", ())),
        "signal_output_info": _port_info(getattr(cls, "SIGNAL_OUTPUTS", ())),
        "params": params,
        "equations": list(eqs),
    }


def input_unit(cls, port) -> str:
    """The unit a signal input expects; "*" for any unit."""
    return str(getattr(port, "unit", "1") or "1")
