"""PlantSpec, ComponentSpec, SimulationSettings: a plant as validated, picklable
plain data (no component instances, no media), and ``build_plant(spec) -> Plant``.

TOML -> ``dnasim.plant.plantfile`` -> PlantSpec; Python -> PlantSpec directly. Both
end in ``build_plant``, which constructs the components through the Python API
(``Component(name, **params)``, where ``Param`` converts unit strings and checks
ranges) and wires them in a ``Plant``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

from dnasim.core.errors import PlantError, Problems
from dnasim.core.units import STANDARD_ATMOSPHERE
from dnasim.core.values import LIMITS, limit_message, t_eval_problem

__all__ = [
    "LIMITS",
    "Problems",
    "ComponentSpec",
    "PlantSpec",
    "SimulationSettings",
    "build_plant",
    "limit_message",
    "output_point_count",
    "setting_problem",
    "t_eval_problem",
]


def setting_problem(name: str, x) -> str | None:
    """What is wrong with the value ``x`` (SI) of the ``[simulation]`` setting ``name``,
    or None: the one statement of the rules, for the plant file (``plantfile``, which
    adds the file, table, key and line) and the command line's options (``--rtol``,
    ``--t-end``, ...). The solver checks its own arguments again, because
    ``solve_dae`` is also called on a bare DAE with no settings."""
    if name in ("t_end", "output_interval", "max_step"):
        return None if x > 0 and not math.isnan(x) else f"must be positive (got {x:g} s)"
    if name == "t_start":
        return None if x >= 0 and math.isfinite(x) else f"must not be negative (got {x:g} s)"
    if name == "rtol":
        return None if 0 < x < 1 else f"must be > 0 and < 1 (got {x:g})"
    if name == "atol_scaled":
        return None if x > 0 and math.isfinite(x) else f"must be a finite number > 0 (got {x:g})"
    if name == "max_order":
        if isinstance(x, bool) or not isinstance(x, int) or not 1 <= x <= 5:
            return f"expected an integer from 1 to 5, got {x!r}"
        return None
    if name == "max_steps":
        if isinstance(x, bool) or not isinstance(x, int) or x < 1:
            return f"expected a positive integer, got {x!r}"
        if x > LIMITS["max_steps"]:
            return limit_message("max_steps", x, LIMITS["max_steps"])
        return None
    if name == "refine_output":
        return None if isinstance(x, bool) else f"expected true or false, got {x!r}"
    if name == "start":
        if not isinstance(x, str) or x.lower() not in ("steady", "given"):
            return f'expected "steady" or "given", got {x!r}'
        return None
    raise KeyError(name)


def output_point_count(t_start: float, t_end: float, interval: float) -> float:
    """Number of rows an output interval asks for (a float: it may be huge or inf)."""
    ratio = (t_end - t_start) / interval
    if not math.isfinite(ratio):
        return math.inf
    return math.floor(ratio + 1e-9) + 1.0


@dataclass
class SimulationSettings:
    """The ``[simulation]`` table, in SI."""

    t_end: float = 100.0
    t_start: float = 0.0
    output_interval: float | None = None
    #: the output times [s] (strictly increasing, within [t_start, t_end]); the rows are
    #: exactly these times (``simulate``'s ``t_eval``); not with ``output_interval``
    t_eval: tuple[float, ...] | None = None
    rtol: float = 1e-6
    atol_scaled: float = 1e-6  # atol_i = atol_scaled * max(nominal_i, |y0_i|)
    max_order: int = 4
    start: str = "steady"
    max_step: float | None = None
    max_steps: int | None = None
    #: solve the algebraic variables at output points between steps (docs/plant_files.md)
    refine_output: bool = True

    def output_points(self) -> float | None:
        """How many rows ``t_eval`` or ``output_interval`` asks for (None: every
        accepted step)."""
        if self.t_eval is not None:
            return float(len(self.t_eval))
        if self.output_interval is None:
            return None
        return output_point_count(self.t_start, self.t_end, self.output_interval)

    def check_output_points(self) -> None:
        """Raise ``PlantError`` when ``output_interval`` asks for more rows than
        ``LIMITS["output_points"]`` (checked before any grid is built), or when
        ``t_eval`` breaks ``t_eval_problem``'s rules or comes with ``output_interval``
        (for a t_start or t_end changed after the file was read: ``--t-end``)."""
        if self.t_eval is not None:
            if self.output_interval is not None:
                raise PlantError(
                    "[simulation] t_eval and output_interval: give one of them, not both"
                )
            problem = t_eval_problem(self.t_eval, self.t_start, self.t_end)
            if problem:
                raise PlantError(f"[simulation] t_eval: {problem}")
            return
        n = self.output_points()
        limit = LIMITS["output_points"]
        if n is not None and not n <= limit:
            raise PlantError(
                f"[simulation] output_interval = {self.output_interval:g} s from "
                f"{self.t_start:g} s to t_end = {self.t_end:g} s asks for {n:g} output "
                f"points, above the limit of {limit:g}; choose a longer output_interval or "
                "a shorter t_end"
            )

    def output_times(self):
        """The output times [s]: ``t_eval``, or the grid of ``output_interval`` closed
        by t_end (None: every accepted step); raises ``PlantError`` above
        ``LIMITS["output_points"]`` rows."""
        import numpy as np

        if self.t_eval is not None:
            self.check_output_points()
            return np.array(self.t_eval, dtype=float)
        if self.output_interval is None:
            return None
        self.check_output_points()
        n = int(self.output_points()) - 1
        t = self.t_start + self.output_interval * np.arange(n + 1)
        if t[-1] < self.t_end - 1e-9 * max(1.0, abs(self.t_end)):
            t = np.append(t, self.t_end)
        return t


@dataclass
class ComponentSpec:
    """One component: its name, its type (a registry name), parameters (numbers,
    unit strings such as "120 bar", time functions, strings), ports (port -> node)
    and inputs (signal input -> "component.output"). ``cls`` is filled from the
    registry when not given."""

    name: str
    type: str
    params: dict[str, Any] = field(default_factory=dict)
    ports: dict[str, str] = field(default_factory=dict)
    inputs: dict[str, str] = field(default_factory=dict)
    cls: type | None = None
    description: str = ""
    instance: Any = None
    fluid_ports: list[str] = field(default_factory=list)
    signal_inputs: list[str] = field(default_factory=list)
    signal_outputs: list[str] = field(default_factory=list)

    def component_class(self) -> type:
        """The component class: ``cls``, else the registry's entry for ``type``."""
        if self.cls is not None:
            return self.cls
        from dnasim.plant.plugins import registry

        REGISTRY = registry()
        try:
            return REGISTRY[self.type]
        except KeyError:
            raise PlantError(
                f"component '{self.name}': unknown type '{self.type}'; known: "
                f"{', '.join(sorted(REGISTRY))}"
            ) from None


@dataclass
class PlantSpec:
    """A plant as plain data, before any ``Plant`` is built: from a plant file
    (``dnasim.plant.plantfile.parse_plant``, validated there with file/table/key/line
    locations) or from Python::

        spec = PlantSpec("demo", components=[
            ComponentSpec("src", "PressureBoundary", params={"p": "2 bar", "T": "600 K"},
                          ports={"port": "a"}), ...], medium="Air")
        plant = spec.build()

    Parameters from Python are validated when the components are built, by the
    same ``Param`` rules (``Param.si_value``, ``Param.range_problem``)."""

    name: str
    description: str = ""
    simulation: SimulationSettings = field(default_factory=SimulationSettings)
    components: list[ComponentSpec] = field(default_factory=list)
    medium: str | None = None
    path: str = "<python>"
    #: modules named by the plant file's ``[plant] import`` (component plugins)
    imports: list[str] = field(default_factory=list)
    #: the site's ambient pressure [Pa] (``[plant] atmosphere``): the zero of the gauge
    #: units ("5 barg", "70 psig") in the parameters and in sweep cases
    atmosphere: float = STANDARD_ATMOSPHERE
    #: guesses of node states for the start, node -> {"p": ..., "T": ... or "h": ...}
    #: (numbers in SI or unit strings; ``PlantGraph.guess_node``)
    nodes: dict[str, dict[str, Any]] = field(default_factory=dict)

    def build(self):
        """The ``Plant`` (raises ``PlantError`` naming every problem)."""
        return build_plant(self)


def build_plant(spec: PlantSpec):
    """Turn a validated spec into a ``Plant`` through the plant model's Python API."""
    from dnasim.plant.plant import Plant

    errors = Problems(spec.path, None)
    plant = Plant(spec.name, medium=spec.medium) if spec.medium else Plant(spec.name)
    # gauge pressures given as strings ("5 barg") are read against the plant's atmosphere
    # (a plant file's values are SI already); the standard one is every component's default
    site = {} if spec.atmosphere == STANDARD_ATMOSPHERE else {"atmosphere": spec.atmosphere}
    for c in spec.components:
        try:
            comp = (
                c.instance
                if c.instance is not None
                else c.component_class()(c.name, **site, **c.params)
            )
        except PlantError as exc:
            errors.add(("components", c.name), None, str(exc))
            continue
        except (TypeError, ValueError) as exc:
            errors.add(("components", c.name), None, f"{c.type} refused its parameters: {exc}")
            continue
        plant.add(comp)
    errors.raise_if_any()
    for c in spec.components:
        for port, node in c.ports.items():
            try:
                plant.connect(f"{c.name}.{port}", node)
            except PlantError as exc:
                errors.add(("components", c.name, "ports"), port, str(exc))
    for c in spec.components:
        for inp, src in c.inputs.items():
            try:
                plant.link(src, f"{c.name}.{inp}")
            except PlantError as exc:
                errors.add(("components", c.name, "inputs"), inp, str(exc))
    for node, guess in spec.nodes.items():
        try:
            plant.guess_node(node, **guess)
        except (PlantError, TypeError) as exc:
            errors.add(("nodes", node), None, str(exc))
    errors.raise_if_any()
    # the plant's own copy of the settings (``Plant.simulate`` uses them): the plant
    # keeps no reference into the spec it was built from
    plant.simulation = replace(spec.simulation)
    return plant
