"""Consistent initial values (y0, y'0) of a compiled ``System``.

    y0, yp0 = initial_values(system, t0=0.0, start="steady")

start="steady": F(t0, y, 0) = 0 for the accumulators' derivatives too (every
storage at rest); start="given": the components' given initial states
(differential variables fixed), the algebraic variables and y' solved. The
starting point is ``initial_guess``; the Newton iteration is
``dnasim.initialization.solve_mixed``. The discrete modes (``System.modes``) are
reset first and chosen to fit the initial values (at most 3 passes).
"""

from __future__ import annotations

import numpy as np

from dnasim.errors import PlantError

__all__ = ["initial_values", "reinitialise"]


def initial_values(system, t0: float = 0.0, start: str = "steady"):
    """(y0, yp0) consistent at t0; raises ``DAEError`` when Newton fails."""
    from dnasim.initial_guess import initial_guess
    from dnasim.initialization import solve_mixed

    if start not in ("steady", "given"):
        raise PlantError(f"start must be 'steady' or 'given', got {start!r}")
    system.reset_modes()
    y = initial_guess(system, t0, steady=start == "steady")
    yp = np.zeros(system.n)
    unknown = ~system.accumulator if start == "steady" else system.algebraic.copy()
    what = f"{start} start of plant '{system.name}'"
    mode_changes: list[str] = []  # components that left their mode at a steady state found
    for attempt in range(3):
        try:
            try:
                y, yp = solve_mixed(system, t0, y, yp, unknown, what=what)
            except PlantError as first:
                if start != "steady" or attempt > 0:
                    raise
                y, yp = _steady_from_interpolated_guess(system, t0, unknown, what, first)
        except PlantError as err:
            if start != "steady":
                raise
            state = getattr(err, "state", None)
            causes = mode_changes or (switch_problems(system, t0, *state) if state else [])
            if state:
                causes = causes + node_problems(system, state[0]) + flow_problems(system, state[0])
            if not causes:
                raise
            raise PlantError(_steady_message(system, t0, causes, bool(mode_changes), err)) from None
        changed = False
        for b in system.blocks:
            before = dict(b.modes)
            if b.comp.init_discrete_state(t0, b.local(y), b.local(yp)):
                changed = True
                mode_changes.append(_mode_change(b, before, y))
        if not changed:
            break
    return y, yp


def _steady_from_interpolated_guess(system, t0, unknown, what, first):
    """The steady start's second try, from node pressures interpolated between the
    boundaries (``initial_guess(..., interpolate=True)``); raises ``first``, the
    first try's error, when this one fails too.

    Why a second guess: the first copies a boundary's pressure into the nodes
    downstream of it, so a valve between two such nodes starts at dp = 0, where its
    flow m = C z sqrt(dp) does not depend on its opening. A controller driving that
    valve is then a null column of the Jacobian (pressure_loop, flow_loop: pid.m_I,
    pid.v, pid.z against the rows pid.integral, pid.output; smallest singular value
    6e-11). The interpolated guess gives every valve a pressure difference. It is
    not the first try because equal weights put the pressure drop anywhere: in
    plants/superheater_line.toml it spreads the drop of the turbine valve over the
    superheaters and Newton finds a reverse-flow solution."""
    from dnasim.initial_guess import initial_guess
    from dnasim.initialization import solve_mixed

    system.reset_modes()
    y = initial_guess(system, t0, interpolate=True, steady=True)
    try:
        return solve_mixed(system, t0, y, np.zeros(system.n), unknown, what=what)
    except PlantError:
        raise first from None


# ------------------------------------------------------------------ steady-start diagnosis
#
# A steady start that fails usually has a physical reason that the Newton message
# (a singular Jacobian, residuals by equation name) does not say: a controller that
# would have to leave its output range to hold its set point at rest (then there is
# no steady state: a saturated PI controller's integral keeps changing, dm_I/dt =
# KI e != 0), a node state outside the fluid's range, a flow far above its nominal
# value. These functions name them, from the state where Newton stopped.

FLOW_FACTOR = 2.0  # a flow above this many times its m_nominal is reported [-]
CHOKED_RATIO = 0.5  # p_out/p_in below which gas or steam flow through a valve is sonic [-]


def _values(block, y, limit=6) -> str:
    x = block.local(y)
    own = [n for n in block.local_names if "." not in n][:limit]
    return ", ".join(f"{block.comp.name}.{n} = {x[n]:.4g}" for n in own)


def _mode_change(block, before: dict, y) -> str:
    after = dict(block.modes)
    changes = ", ".join(f"{k} '{before.get(k)}' -> '{v}'" for k, v in after.items())
    return (
        f"component '{block.comp.name}' ({type(block.comp).__name__}) would have to leave its "
        f"range: at the steady state found with {changes} it switches ({_values(block, y)}), "
        "and in the new mode the plant has no steady state"
    )


def switch_problems(system, t, y, yp) -> list[str]:
    """Components whose mode-changing switch function is negative at (y, yp): a
    controller whose output lies beyond its limits there."""
    out = []
    for b in system.blocks:
        x, xp = b.local(y), b.local(yp)
        for sw in b.comp.switches():
            if sw.action is None or sw.size != 1:
                continue
            try:
                g = float(sw.function(t, x, xp))
            except Exception:  # noqa: BLE001 - a diagnosis must not hide the real error
                continue
            if g < 0.0:
                out.append(
                    f"component '{b.comp.name}' ({type(b.comp).__name__}) is beyond its switch "
                    f"'{sw.name}' ({sw.doc}; g = {g:.4g} < 0: {_values(b, y)}), so a steady "
                    "state would need it outside its range"
                )
    return out


def node_problems(system, y) -> list[str]:
    """Node states (p, h) outside their fluid's range at y."""
    from dnasim.errors import DnasimError

    out = []
    for node, k in system.node_index.items():
        medium = system.node_media.get(node)
        if medium is None:
            continue
        p, h = float(y[k]), float(y[k + 1])
        try:
            medium.state(p, h)
        except (DnasimError, ValueError, ArithmeticError) as err:
            out.append(
                f"node '{node}' has p = {p:.4g} Pa, h = {h:.4g} J/kg, outside the range of "
                f"{medium.label} ({err})"
            )
    return out[:4]


def flow_problems(system, y) -> list[str]:
    """Mass flows above FLOW_FACTOR times their nominal value at y, with the pressure
    ratio across a valve when gas or steam would be choked there."""
    ratios = []
    for i, name in enumerate(system.names):
        nominal = system.nominal[i]
        if system.units.get(name) == "kg/s" and nominal > 0 and abs(y[i]) > FLOW_FACTOR * nominal:
            ratios.append((abs(y[i]) / nominal, i, name))
    out = []
    seen = set()
    for ratio, i, name in sorted(ratios, reverse=True):
        comp = name.split(".")[0]
        if comp in seen or len(out) >= 3:
            continue
        seen.add(comp)
        text = f"{name} = {y[i]:.4g} kg/s is {ratio:.3g} times its nominal value"
        text += _choked(system, comp, y)
        out.append(text)
    return out


def _choked(system, comp: str, y) -> str:
    """A note when ``comp`` is a restriction (inlet and outlet ports) passing gas or
    steam at a pressure ratio below CHOKED_RATIO."""
    try:
        node_in = system.connections[(comp, "inlet")]
        node_out = system.connections[(comp, "outlet")]
    except KeyError:
        return ""
    k_in, k_out = system.node_index[node_in], system.node_index[node_out]
    p_in, p_out, h_in = float(y[k_in]), float(y[k_out]), float(y[k_in + 1])
    if not (p_in > 0 and p_out / p_in < CHOKED_RATIO):
        return ""
    medium = system.node_media.get(node_in)
    if medium is not None and medium.condensable:
        try:
            _, h_vap = medium.saturation_enthalpies(np.array([p_in]))
            if not float(h_vap[0]) <= h_in:  # a liquid, or above the critical pressure
                return ""
        except Exception:  # noqa: BLE001 - only a note
            return ""
    return (
        f"; the pressure ratio across '{comp}' is p_out/p_in = {p_out:.4g} Pa / {p_in:.4g} Pa "
        f"= {p_out / p_in:.3g}: a gas or steam flow is sonic (choked) below about "
        f"{CHOKED_RATIO}, and the flow model (which grows with sqrt(p_in - p_out) without "
        "limit) no longer holds"
    )


def _steady_message(system, t0, causes, after_switch: bool, err) -> str:
    where = "at the steady state found first" if after_switch else "where Newton stopped"
    return (
        f"At t = {t0:.10g}, steady start of plant '{system.name}': no steady state found. "
        f"The likely cause ({where}): "
        + "; ".join(causes)
        + ". Check the boundary conditions (pressures, temperatures, flows) and the "
        'controllers\' ranges, or start from given initial states (start = "given"). '
        f"The solver's report: {err}"
    )


def reinitialise(system, t: float, y, yp):
    """Consistent (y, yp) after a jump at t, the differential variables kept (the
    algebraic ones and y' solved): the restart of a backend without its own."""
    from dnasim.initialization import solve_mixed

    return solve_mixed(system, t, y, yp, system.algebraic.copy(), what="restart")
