"""The steady start: the plant at rest, found whenever a state at rest exists.

    rest = find_steady_state(system, t0)     # SteadyState: y, yp, stats, saturated, notes

A state at rest solves F(t0, y, 0) = 0: every storage balanced, every controller's
integral still (``dnasim.start.initial.initial_values(system, t0, "steady")`` and ``dnasim
steady`` both come here). Two kinds of variables keep their value and have their
derivative solved instead: the accumulators (running integrals M_passed, H_passed,
Q_passed, W, which nothing reads) and the states ``Component.free_at_rest`` names in
the current mode (a saturated PI controller's held integral: its output is the limit,
no equation reads the integral).

How it is found (each stage only when the one before failed):

1. **Newton from three guesses** in turn (``initial_guess``, the plant file's node
   guesses winning over the rest): the components' guesses with the node pressures
   copied along the streams; the same with the unguessed pressures interpolated
   between the guessed ones (these two were the steady start before, so a plant they
   solve keeps its numbers); the march (enthalpies along the flow, pressures through
   pipes and vessels before valves, set points as guesses of what they measure). The
   controllers are free of their limits; ``dnasim.start.consistent.solve_mixed``, the
   globalised Newton of every start. Most plants end here.
2. **Pseudo-transient continuation** (Kelley and Keyes 1998; the "false transient"
   of process simulators): the plant's own dynamics, the time frozen at t0, integrated
   towards rest by implicit Euler with pseudo time steps that grow by up to 4 per
   step, from the march's state made consistent (its algebraic variables solved, the
   differential ones as guessed: the given start's where components have initial
   values).
   Each step is a Newton iteration on F(t0, y, (y - y_k)/dt) = 0 with the Jacobian
   dF/dy + dF/dy'/dt from the two finite-difference Jacobians, kept while Newton
   converges; a step whose Newton fails is retried with dt/4. The controllers' limits
   and the phase modes act as in a run (a switch function that turned negative over a
   step changes its mode before the next). The end is a step of dt >= 1e7 s that moves
   no variable by more than 1e-6 of its scale; the rest Newton from there finishes
   (in a closed loop, whose inventory the steady equations do not fix, the last
   pseudo step is the result: its inventory is the given start's).
3. **Modes at rest**: a controller's limit is engaged when the steady state without
   limits (stage 1, or the rest Newton with the controllers free from stage 2's end)
   lies beyond it: the switch functions with a mode action (a PI controller's upper
   and lower) are evaluated at the state at rest, a negative one changes its mode,
   the state is solved again (Newton, else pseudo-transient in the new modes) and
   checked again, until every switch holds. A saturated controller whose switch then
   asks to leave the limit (the error turned) has no mode that balances: no state at
   rest inside its range. A cycle of modes stops the same way.
4. **Ranges**: ``Component.steady_problems`` of every component at the result (a
   sink-only boundary that would feed the plant, a check valve passing reverse flow,
   a vessel over-full or empty, a controller output outside [z_min, z_max]). Any
   problem stops the start with a ``SteadyStateError`` naming it.

A start that fails raises ``SteadyStateError`` (a ``PlantError``): one paragraph
naming the components, variables and the likely physical cause, and what to try
(``steady_message``). A failed continuation is examined for a balance that closes for
no value of its own state (``unclosed_balances``: a drum without level control, whose
pressure the mass balance alone sets, and whose energy balance then misses by a fixed
power whatever its level): such a plant has no state at rest, and the message names
the balance and its miss at rest.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from dnasim.core.errors import DAEError, PlantError, ResidualDomainError
from dnasim.solver.linear_algebra import SQRT_EPS, SingularMatrixError

__all__ = ["SteadyState", "SteadyStateError", "SteadyStats", "find_steady_state"]

#: relative tolerance of the pseudo-transient steps' Newton iteration (their weights
#: 1 / (RTOL |y| + RTOL nominal)); the rest Newton at the end is solve_mixed's (1e-9)
RTOL = 1e-6
#: a pseudo step's Newton iteration has converged when its scaled step is below this
NEWTON_TOL = 0.1
#: iterations of one pseudo step's Newton before the step is retried with dt/4; the
#: Jacobians are taken again when a step shrinks by less than RATE_REFRESH. Measured
#: on plants/rankine.toml and the feed line of tests/plants (residual evaluations of
#: the two continuations): 8 iterations and growth by 1.2 after 5 of them 6034; 12
#: and growth 4 / 2 / 1.3 after up to 3 / 6 / more iterations 1112 (16 or 24: the same)
MAX_NEWTON = 12
RATE_REFRESH = 0.3
#: first pseudo time step [s]; the smallest [s] before the continuation gives up
DT0 = 1e-3
DT_MIN = 1e-10
#: largest pseudo time step [s]; the continuation is at rest after a step of at least
#: DT_REST [s] that moved no variable by more than RTOL of its scale
DT_MAX = 1e10
DT_REST = 1e7
#: pseudo time steps before the continuation gives up
MAX_PSEUDO_STEPS = 600
#: passes of the mode selection at rest (stage 3)
MAX_MODE_PASSES = 8


class SteadyStateError(PlantError):
    """No state at rest found, or none inside the components' ranges. ``state``: the
    last iterate (y, yp) when there is one."""

    state = None


@dataclass
class SteadyStats:
    """Work of one steady start: residual evaluations (finite-difference Jacobians
    included), Jacobians, pseudo time steps (accepted, rejected), CPU seconds, and the
    stage that found the state ("newton", "pseudo-transient")."""

    residual_evals: int = 0
    jacobians: int = 0
    newton_iterations: int = 0
    pseudo_steps: int = 0
    rejected_steps: int = 0
    mode_passes: int = 0
    method: str = ""
    cpu: float = 0.0

    def as_dict(self) -> dict:
        return {k: v for k, v in self.__dict__.items() if not k.startswith("_")}


@dataclass
class SteadyState:
    """A state at rest: y [SI], yp (0 but for the accumulators and the free states),
    the saturated controllers ``saturated`` [(component, mode)], ``notes`` (plain
    sentences for the user, e.g. a controller that holds a limit), ``stats``."""

    y: np.ndarray
    yp: np.ndarray
    stats: SteadyStats
    saturated: list = field(default_factory=list)
    notes: list = field(default_factory=list)


class _Counted:
    """The System's residual, counted into ``stats`` (``IterationMatrix`` is given the
    System's ``residual_for_columns`` by ``_CountedSystem`` and counts partial
    evaluations into ``stats.residual_evals``)."""

    def __init__(self, residual, stats):
        self.residual = residual
        self.stats = stats

    def __call__(self, t, y, yp):
        self.stats.residual_evals += 1
        return self.residual(t, y, yp)


class _CountedSystem:
    """What ``solve_mixed`` reads of a System, with the residual counted, and the
    iteration matrix on its sparsity, made once for the whole start (its colouring and
    band ordering cost more than the Newton iterations on a 10000-volume pipe)."""

    def __init__(self, system, stats):
        from dnasim.start.consistent import iteration_matrix

        self.residual = _Counted(system.residual, stats)
        self.residual_for_columns = system.residual_for_columns
        self.nominal = system.nominal
        self.pattern_y = system.pattern_y
        self.pattern_yp = system.pattern_yp
        self.names = system.names
        self.eq_names = system.eq_names
        self.matrix = iteration_matrix(self)


def _counted(system, stats) -> _CountedSystem:
    """The start's one ``_CountedSystem`` of ``system`` (kept on ``stats``)."""
    dae = getattr(stats, "_dae", None)
    if dae is None or dae.names is not system.names:
        dae = stats._dae = _CountedSystem(system, stats)
    return dae


# ------------------------------------------------------------------------- the whole start


def find_steady_state(system, t0: float = 0.0, y_guess=None) -> SteadyState:
    """The plant ``system`` at rest at t0 [s] (module doc). ``y_guess``: a starting
    point instead of ``initial_guess``'s. Raises ``SteadyStateError``."""
    stats = SteadyStats()
    cpu = time.process_time()
    try:
        rest = _unconstrained(system, t0, y_guess, stats)
        rest = _modes_at_rest(system, t0, rest, stats)
        problems = range_problems(system, t0, rest.y)
        if problems:
            err = SteadyStateError(_range_message(system, t0, problems))
            err.state = (rest.y, rest.yp)
            raise err
        rest.notes += _saturation_notes(system, t0, rest) + choked_valve_notes(system, rest.y)
        return rest
    finally:
        stats.cpu = time.process_time() - cpu


def _guesses(system, t0, y_guess):
    """The starting points of stage 1, in turn: the components' guesses (node
    pressures copied along the streams), the same with the unguessed node pressures
    interpolated between the guessed ones, and the march (``initial_guess`` with
    ``march``: enthalpies along the flow, set points as guesses). The first two are
    the steady start's before the continuation existed, so that a plant they solve
    keeps its numbers to the bit."""
    from dnasim.start.guess import initial_guess

    if y_guess is not None:
        yield "given guess", np.array(y_guess, dtype=float)
        return
    for label, kw in (
        ("guess", {}),
        ("interpolated guess", {"interpolate": True}),
        ("march", {"march": True}),
    ):
        system.reset_modes()
        try:
            y = initial_guess(system, t0, steady=True, **kw)
        except ResidualDomainError:
            continue
        yield label, y


def _unconstrained(system, t0, y_guess, stats) -> SteadyState:
    """Stages 1 and 2: a state at rest with the controllers free of their limits when
    one is found; else the end of the pseudo-transient continuation (its modes as the
    dynamics left them)."""
    first, last = None, None
    for label, y in _guesses(system, t0, y_guess):
        last = y
        try:
            y1, yp1 = rest_newton(system, t0, y, stats)
            stats.method = f"newton ({label})"
            return SteadyState(y1, yp1, stats)
        except PlantError as err:
            first = first or err
    if last is None:
        raise SteadyStateError(steady_message(system, t0, first or SteadyStateError("no guess")))
    system.reset_modes()
    try:
        y2, yp2 = pseudo_transient(system, t0, last, stats)
    except SteadyStateError as err:
        out = SteadyStateError(steady_message(system, t0, err, first, stats=stats, guess=last))
        out.state = err.state
        raise out from None
    stats.method = "pseudo-transient"
    # the controllers free of their limits from there (stage 3 needs that state)
    modes = _save_modes(system)
    _free_switch_modes(system)
    try:
        y3, yp3 = rest_newton(system, t0, y2, stats)
        return SteadyState(y3, yp3, stats)
    except PlantError:
        _restore_modes(system, modes)
    try:
        y4, yp4 = rest_newton(system, t0, y2, stats)
        return SteadyState(y4, yp4, stats)
    except PlantError:
        return SteadyState(y2, yp2, stats)  # a closed loop: the pseudo step's state


def _range_message(system, t0, problems) -> str:
    return (
        f"At t = {t0:.10g}, steady start of plant '{system.name}': the plant has no state at "
        "rest inside its components' ranges: " + "; ".join(problems) + "."
    )


@dataclass
class ModeChange:
    """A switch block leaving its mode at a state at rest: ``component``, the modes
    ``before`` and ``after``, the ``switch`` and its value ``g`` there."""

    component: str
    before: dict
    after: dict
    switch: str
    g: float

    def __str__(self) -> str:
        diff = ", ".join(
            f"'{self.before.get(k)}' -> '{v}'"
            for k, v in self.after.items()
            if self.before.get(k) != v
        )
        return f"{self.component}: {diff}"


def _modes_at_rest(system, t0, rest: SteadyState, stats) -> SteadyState:
    """Stage 3 (module doc): engage the limits the state at rest lies beyond, solve
    again, until every mode switch holds."""
    seen = {_mode_key(system)}
    states = [rest]  # the states at rest in turn, the first with the controllers free
    history: list[list[ModeChange]] = []
    for _ in range(MAX_MODE_PASSES):
        changes = switch_modes(system, t0, rest.y, rest.yp)
        if not changes:
            rest.saturated = saturated_controllers(system)
            return rest
        stats.mode_passes += 1
        history.append(changes)
        key = _mode_key(system)
        if key in seen:
            raise SteadyStateError(_no_balance_message(system, t0, states, history))
        seen.add(key)
        y = np.array(rest.y, dtype=float)
        try:
            y1, yp1 = rest_newton(system, t0, y, stats)
        except PlantError:
            try:
                y1, yp1 = pseudo_transient(system, t0, y, stats, switch_modes_on=False)
            except SteadyStateError as err:
                raise SteadyStateError(
                    _no_balance_message(system, t0, states, history, err)
                ) from None
        rest = SteadyState(y1, yp1, stats)
        states.append(rest)
    raise SteadyStateError(_no_balance_message(system, t0, states, history))


# ------------------------------------------------------------------------------ stage 1


def fixed_mask(system, t0, y) -> np.ndarray:
    """True where y keeps its value at rest and y' is solved instead: the accumulators
    and the states ``Component.free_at_rest`` names in the current modes."""
    fixed = system.accumulator.copy()
    for b in system.blocks:
        names = b.comp.free_at_rest(t0, b.local(y))
        for name in names:
            fixed[b.gidx[b.index[name]]] = True
    return fixed


def rest_newton(system, t0, y, stats, *, max_iter=60, hold=()):
    """Newton on F(t0, y, 0) = 0 from y (``solve_mixed``), the state modes (phases)
    updated from the solution and solved again when they change (at most 3 times).
    ``hold``: indices of states that keep their value too, their derivative solved
    (``unclosed_balances``). Returns (y, yp); raises PlantError."""
    from dnasim.start.consistent import solve_mixed

    dae = _counted(system, stats)
    y = np.array(y, dtype=float)
    for _ in range(3):
        fixed = fixed_mask(system, t0, y)
        fixed[list(hold)] = True
        yp = np.zeros(system.n)
        y, yp = solve_mixed(
            dae, t0, y, yp, ~fixed, max_iter=max_iter, what=_what(system), matrix=dae.matrix
        )
        if not state_modes(system, t0, y, yp):
            return y, yp
    return y, yp


def _what(system) -> str:
    return f"steady start of plant '{system.name}'"


# ------------------------------------------------------------------------------ stage 2


def pseudo_transient(system, t0, y, stats, *, switch_modes_on=True):
    """Stage 2 (module doc): implicit Euler in pseudo time from y towards rest, the
    time frozen at t0. ``switch_modes_on``: the mode switches (controllers' limits) act
    as in a run; otherwise only the state modes (phases) follow the state. Returns
    (y, yp) at rest; raises SteadyStateError (``state``: the last accepted state)."""
    from dnasim.start.consistent import solve_mixed

    n = system.n
    dae = _counted(system, stats)
    residual, matrix = dae.residual, dae.matrix
    nominal = np.asarray(system.nominal, dtype=float)
    y_k = np.array(y, dtype=float)
    yp_k = np.zeros(n)
    # the given-start state made consistent first: its algebraic variables solved, so
    # that the first pseudo steps follow the dynamics instead of jumping to consistency
    try:
        y_k, yp_k = solve_mixed(
            dae,
            t0,
            y_k,
            yp_k,
            system.algebraic.copy(),
            what=_what(system),
            matrix=matrix,
        )
    except PlantError:
        pass
    fixed = fixed_mask(system, t0, y_k)
    dt = DT0
    jac = None
    last_problem = ""
    for _ in range(MAX_PSEUDO_STEPS):
        ok, y_new, yp_new, iters, jac, last_problem = _pseudo_step(
            residual, matrix, t0, y_k, yp_k, dt, fixed, nominal, jac, stats
        )
        if not ok:
            stats.rejected_steps += 1
            dt *= 0.25
            jac = None
            if dt < DT_MIN:
                break
            continue
        stats.pseudo_steps += 1
        w = (~fixed) / (RTOL * np.abs(y_new) + RTOL * nominal)
        change = float(np.max(np.abs(y_new - y_k) * w))
        y_k, yp_k = y_new, yp_new
        changed = state_modes(system, t0, y_k, yp_k)
        if switch_modes_on:
            changed = bool(switch_modes(system, t0, y_k, yp_k)) or changed
        if changed:
            fixed = fixed_mask(system, t0, y_k)
            jac = None
            continue
        if dt >= DT_REST and change <= 1.0:
            return y_k, yp_k
        grow = 4.0 if iters <= 3 else 2.0 if iters <= 6 else 1.3
        dt = min(dt * grow, DT_MAX)
    err = SteadyStateError(
        "the pseudo-transient continuation did not come to rest "
        f"({last_problem or 'the most steps'}; "
        f"pseudo time step {dt:.3g} s)"
    )
    err.state = (y_k, yp_k)
    raise err


def _jacobians(matrix, t, y, yp, f, nominal, stats):
    """(dF/dy, dF/dy') by finite differences on the sparsity's colouring."""
    inc = np.maximum(SQRT_EPS * np.abs(y), RTOL * nominal)
    inc = (y + inc) - y
    jy = matrix.finite_difference(t, y, yp, f, inc, 1.0, 0.0)
    incp = np.maximum(SQRT_EPS * np.abs(yp), RTOL * nominal)
    incp = (yp + incp) - yp
    jyp = matrix.finite_difference(t, y, yp, f, incp, 0.0, 1.0)
    stats.jacobians += 1
    return jy, jyp


def _evaluate(residual, t, y, yp):
    try:
        f = residual(t, y, yp)
    except ResidualDomainError:
        return None
    return f if np.all(np.isfinite(f)) else None


def _pseudo_step(residual, matrix, t, y_k, yp_k, dt, fixed, nominal, jac, stats):
    """One implicit Euler step F(t, y, y') = 0 with y' = (y - y_k)/dt for the free
    variables and y = y_k, y' unknown for the fixed ones. Returns (ok, y, yp,
    iterations, Jacobians to keep, problem)."""
    ymask = (~fixed).astype(float)
    ypmask = fixed.astype(float)
    y = y_k.copy()
    yp_fixed = np.where(fixed, yp_k, 0.0)

    def yp_of(y, yp_fixed):
        return np.where(fixed, yp_fixed, (y - y_k) / dt)

    f = _evaluate(residual, t, y, yp_of(y, yp_fixed))
    if f is None:
        return False, y, None, 0, None, "the residual cannot be evaluated"
    fresh, lu_dt, norm_old, it = False, None, np.inf, 0
    uw = ymask / (RTOL * np.abs(y_k) + RTOL * nominal)
    while it < MAX_NEWTON:
        if jac is None:
            jac = _jacobians(matrix, t, y, yp_of(y, yp_fixed), f, nominal, stats)
            fresh, lu_dt = True, None
        if lu_dt != dt:
            jy, jyp = jac
            cols = np.repeat(np.arange(jy.shape[1]), np.diff(jy.indptr))
            data = jy.data * ymask[cols] + jyp.data * (ymask / dt + ypmask)[cols]
            matrix.matrix = sp.csc_matrix((data, jy.indices, jy.indptr), shape=jy.shape)
            try:
                matrix.factorize()
            except SingularMatrixError:
                if fresh:
                    return False, y, None, it, None, "a singular Jacobian"
                jac = None
                continue
            lu_dt = dt
        d = matrix.solve(-f)
        norm = float(np.sqrt(np.mean((d * uw) ** 2)))
        if not np.isfinite(norm) or (norm > RATE_REFRESH * norm_old and not fresh):
            if fresh:
                return False, y, None, it, None, "Newton diverged"
            jac = None
            continue
        lam = 1.0
        while True:
            y_new = y + lam * d * ymask
            yp_fixed_new = yp_fixed + lam * d * ypmask
            f_new = _evaluate(residual, t, y_new, yp_of(y_new, yp_fixed_new))
            if f_new is not None or not fresh:
                break
            lam *= 0.5
            if lam < 1e-3:
                break
        if f_new is None:
            if fresh:
                return False, y, None, it, None, "a state outside the model's domain"
            jac = None
            continue
        it += 1
        stats.newton_iterations += 1
        y, yp_fixed, f = y_new, yp_fixed_new, f_new
        if norm <= NEWTON_TOL and lam == 1.0:
            return True, y, yp_of(y, yp_fixed), it, jac, ""
        norm_old = norm if lam == 1.0 else np.inf
        fresh = False
    return False, y, None, it, None, "Newton did not converge"


# ------------------------------------------------------------------------------- modes


def _switch_block(block) -> bool:
    """A block whose modes follow its scalar switch functions with actions (controllers,
    limiters); the other blocks' modes (phases, table segments) follow the state
    (``init_discrete_state``)."""
    return any(_mode_switch(sw) for sw in block.comp.switches())


def _mode_switch(sw) -> bool:
    """A scalar switch whose action changes the component's equations (not a notice)."""
    return sw.action is not None and sw.size == 1 and not sw.notice


def state_modes(system, t0, y, yp) -> bool:
    """The state-determined modes (phases of pipe volumes, table segments) chosen from
    (y, yp) by ``init_discrete_state``; True when one changed."""
    changed = False
    for b in system.blocks:
        if not _switch_block(b):
            changed = b.comp.init_discrete_state(t0, b.local(y), b.local(yp)) or changed
    return changed


def switch_modes(system, t0, y, yp) -> list[ModeChange]:
    """Every scalar mode switch that is negative at (y, yp) takes its action once (a
    controller enters or leaves a limit; its bumpless reset writes y in place)."""
    out = []
    for b in system.blocks:
        if not _switch_block(b):
            continue
        x, xp = b.local(y), b.local(yp)
        for sw in b.comp.switches():
            if not _mode_switch(sw):
                continue
            try:
                g = float(sw.function(t0, x, xp))
            except ResidualDomainError:
                continue
            if g < 0.0:
                before = dict(b.modes)
                sw.action(t0, x, xp)
                if dict(b.modes) != before:
                    out.append(ModeChange(b.comp.name, before, dict(b.modes), sw.name, g))
        y[b.gidx] = x.data
    return out


def _free_switch_modes(system) -> None:
    """The switch blocks back to their default modes (the controllers free)."""
    for b in system.blocks:
        if _switch_block(b):
            b.modes.clear()
            b.comp.reset_discrete_state(b.modes)


def _save_modes(system) -> dict:
    import copy

    return {name: copy.deepcopy(m) for name, m in system.modes.items()}


def _restore_modes(system, saved) -> None:
    for name, m in saved.items():
        system.modes[name].clear()
        system.modes[name].update(m)


def _mode_key(system) -> tuple:
    out = []
    for b in system.blocks:
        if _switch_block(b):
            out.append((b.comp.name, tuple(sorted((k, str(v)) for k, v in b.modes.items()))))
    return tuple(out)


def saturated_controllers(system) -> list[tuple[str, str]]:
    """(component, mode) of the switch blocks not in their default mode "free"."""
    out = []
    for b in system.blocks:
        if _switch_block(b):
            mode = b.modes.get("mode")
            if mode not in (None, "free"):
                out.append((b.comp.name, str(mode)))
    return out


# ------------------------------------------------------------------------------ ranges


def range_problems(system, t0, y) -> list[str]:
    """``Component.steady_problems`` of every component at y."""
    return [text for texts in component_range_problems(system, t0, y).values() for text in texts]


def component_range_problems(system, t0, y) -> dict[str, list[str]]:
    """component -> its ``Component.steady_problems`` at y (the components with any)."""
    out = {}
    for b in system.blocks:
        try:
            texts = b.comp.steady_problems(t0, b.local(y))
        except ResidualDomainError as err:
            texts = [f"component '{b.comp.name}': {err}"]
        if texts:
            out[b.comp.name] = list(texts)
    return out


# ------------------------------------------------------------------------------ messages


def _saturation_notes(system, t0, rest) -> list[str]:
    notes = []
    for name, mode in rest.saturated:
        b = system.block(name)
        x = b.local(rest.y)
        P = b.comp.params
        limit = "z_max" if mode == "high" else "z_min"
        value = P.get(limit, float("nan"))
        text = f"controller '{name}' holds its output at {limit} = {value:g} at rest"
        if "e" in x:
            text += f" (error e = {x['e']:.4g})"
        text += ": its set point is not reached"
        if "m_I" in x:
            rate = b.local(rest.yp)["m_I"]
            if rate != 0.0:
                text += (
                    f"; without anti-windup its integral winds at dm_I/dt = {rate:.3g} per s, "
                    "so the longer it stays saturated, the later it leaves the limit"
                )
        notes.append(text)
    return notes


def choked_valve_notes(system, y) -> list[str]:
    """A note for every ``Valve`` (the square-root law without choking) that passes gas
    or steam at a pressure ratio p_out/p_in below CHOKED_RATIO at y: there the real
    flow is sonic, and the law overestimates it."""
    out = []
    for name, comp in system.components.items():
        if type(comp).__name__ != "Valve" or not _choked(system, name, y):
            continue
        p_in = y[system.node_index[system.connections[(name, "inlet")]]]
        p_out = y[system.node_index[system.connections[(name, "outlet")]]]
        out.append(
            f"valve '{name}' passes {y[system.index[name + '.m']]:.4g} kg/s of gas or steam at "
            f"p_out/p_in = {p_out / p_in:.3g}, where the flow is choked (sonic, below about "
            f"{CHOKED_RATIO}); its law m = C z sqrt(dp) overestimates it there (a ControlValve "
            "models choking)"
        )
    return out


def _no_balance_message(system, t0, states, history, err=None) -> str:
    """No mode of the controllers balances (module doc, stage 3): the range problems at
    the states found (a sink that would feed the plant says more than the controller),
    then each controller's story: the output it would need at rest, the limit, what it
    measures there, and the actuators it drives against their pressure difference."""
    head = f"At t = {t0:.10g}, steady start of plant '{system.name}': "
    found: dict[str, list[str]] = {}
    for st in reversed(states):  # the latest state's problems of each component
        for comp, texts in component_range_problems(system, t0, st.y).items():
            if not _switch_block(system.block(comp)):  # controllers: their story below
                found.setdefault(comp, texts)
    problems = [text for texts in found.values() for text in texts]
    parts = []
    if problems:
        parts.append(
            "the plant has no state at rest inside its components' ranges: " + "; ".join(problems)
        )
    names = list(dict.fromkeys(c.component for changes in history for c in changes))
    stories = [_controller_story(system, t0, name, states, history) for name in names]
    if err is not None:
        stories.append(f"with the limits engaged the plant has no state at rest ({_reason(err)})")
    parts.append("no state at rest inside the controllers' ranges: " + "; ".join(stories))
    return head + ". Moreover, ".join(parts) + "."


def _controller_story(system, t0, name, states, history) -> str:
    b = system.block(name)
    comp = b.comp
    P = comp.params
    first = b.local(states[0].y)
    kind = type(comp).__name__
    demand = first["v"] if "v" in first else first["m_p"] + first["m_I"] if "m_I" in first else None
    entered = next((c for changes in history for c in changes if c.component == name), None)
    mode = entered.after.get("mode") if entered is not None else None
    limit = "z_max" if mode == "high" else "z_min" if mode == "low" else None
    text = f"controller '{name}' ({kind})"
    if demand is not None and limit is not None:
        text += (
            f" would need the output {demand:.4g} at rest, beyond {limit} = {P[limit]:g}, to "
            "hold its set point"
        )
    left = any(
        c.component == name and c.before.get("mode") == mode for changes in history for c in changes
    )
    if limit is not None and len(states) > 1:
        at_limit = b.local(states[min(1, len(states) - 1)].y)
        measured = at_limit["measured"] if "measured" in at_limit else None
        try:
            w = comp.set_point_value(t0, at_limit)
        except Exception:  # noqa: BLE001 - only words
            w = None
        unit = getattr(comp, "measured_unit", "")
        if measured is not None and w is not None:
            text += (
                f"; at {limit} it measures {_shown(measured, unit)} against its set point "
                f"{_shown(w, unit)}"
            )
        if left:
            text += ", so it would leave the limit again: no mode balances"
    for note in _driven_against_pressure(system, name, states):
        text += "; " + note
    return text


def _shown(value, unit) -> str:
    """A measured value for a message: K also in degC, Pa also in bar."""
    if unit == "K":
        return f"{value:.5g} K ({value - 273.15:.4g} degC)"
    if unit == "Pa":
        return f"{value / 1e5:.5g} bar"
    return f"{value:.5g} {unit}".rstrip()


def _driven_against_pressure(system, name, states) -> list[str]:
    """The components driven by controller ``name``'s output whose inlet pressure lies
    below their outlet pressure at the states found: their flow runs backwards for
    every opening in [0, 1]."""
    out = []
    for (dest, _inp), (src, _ref) in system.links.items():
        if src != name:
            continue
        try:
            n_in = system.connections[(dest, "inlet")]
            n_out = system.connections[(dest, "outlet")]
        except KeyError:
            continue
        y = states[-1].y
        p_in, p_out = y[system.node_index[n_in]], y[system.node_index[n_out]]
        if p_in < p_out:
            out.append(
                f"it drives '{dest}', whose inlet pressure {p_in / 1e5:.5g} bar (node '{n_in}') "
                f"lies below its outlet pressure {p_out / 1e5:.5g} bar (node '{n_out}'), so that "
                "fluid flows backwards through it at any opening: check the supply pressure"
            )
    return out


def steady_message(system, t0, err, first=None, stats=None, guess=None) -> str:
    """The failed start in plant terms: a balance that cannot close at rest whatever
    the state (``unclosed_balances``: then the plant has no state at rest, said first);
    where the search stopped (the last state of the continuation, else of the Newton
    iteration from the guess; ``guess``: the start of the search, where
    ``unclosed_balances`` solves first), what is wrong there (controllers beyond their limits,
    node states outside the fluid's range, flows far above their nominal values, a
    choked valve, the balances that do not close) and what to try."""
    state = getattr(err, "state", None) or getattr(first, "state", None)
    causes, unclosed = [], []
    if state is not None:
        y, yp = state
        starts = [y] if guess is None else [np.asarray(guess, dtype=float), y]
        unclosed = unclosed_balances(system, t0, y, stats or SteadyStats(), starts=starts)
        causes += limit_problems(system, t0, y, yp)
        causes += node_problems(system, y)
        causes += flow_problems(system, y)
        causes += no_flow_problems(system, y)
        causes += open_balances(system, t0, y)
    head = f"At t = {t0:.10g}, steady start of plant '{system.name}': "
    if unclosed:
        text = (
            head + "the plant has no state at rest: " + "; ".join(unclosed) + ". A balance "
            "that closes for no value of its own state closes at rest only if the boundary "
            "conditions and heat inputs match exactly: change one of them, or give that "
            "state a control (a drum or tank without a level control keeps its level only "
            f"by such a match). The search: {_reason(err)}."
        )
    else:
        text = head + f"no state at rest found ({_reason(err)})."
    if causes:
        text += " Where the search stopped: " + "; ".join(causes) + "."
    if unclosed:
        return text + ' Or start from given initial states (start = "given")'
    return text + (
        " Check the boundary conditions (pressures, temperatures, flows) and the "
        "controllers' set points and ranges; give guesses for the nodes the search "
        'misjudged ([nodes.<node>] with p = "... bar" and T = "... degC" or h, '
        'docs/plant_files.md), or start from given initial states (start = "given")'
    )


def _reason(err) -> str:
    text = str(err)
    # the solver's own advice is for DAE users, not for plants
    cut = text.find(" If some variables are algebraic")
    return text[:cut] if cut >= 0 else text


FLOW_FACTOR = 2.0  # a flow above this many times its m_nominal is reported [-]
CHOKED_RATIO = 0.5  # p_out/p_in below which gas or steam flow through a valve is sonic [-]


def _values(block, y, limit=6) -> str:
    x = block.local(y)
    own = [n for n in block.local_names if "." not in n][:limit]
    return ", ".join(f"{block.comp.name}.{n} = {x[n]:.4g}" for n in own)


def limit_problems(system, t0, y, yp) -> list[str]:
    """Controllers whose mode switch is negative at (y, yp): an output beyond its
    limits there."""
    out = []
    for b in system.blocks:
        if not _switch_block(b):
            continue
        x, xp = b.local(y), b.local(yp)
        for sw in b.comp.switches():
            if not _mode_switch(sw):
                continue
            try:
                g = float(sw.function(t0, x, xp))
            except Exception:  # noqa: BLE001 - a diagnosis must not hide the real error
                continue
            if g < 0.0:
                out.append(
                    f"'{b.comp.name}' ({type(b.comp).__name__}) is beyond its switch "
                    f"'{sw.name}' ({sw.doc}; {_values(b, y)})"
                )
    return out[:4]


def node_problems(system, y) -> list[str]:
    """Node states (p, h) outside their fluid's range at y."""
    from dnasim.core.errors import DnasimError

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
    if type(system.components[comp]).__name__ in ("ControlValve", "CheckValve"):
        return f"; the pressure ratio across '{comp}' is p_out/p_in = {p_out / p_in:.3g} (choked)"
    return (
        f"; the pressure ratio across '{comp}' is p_out/p_in = {p_out:.4g} Pa / {p_in:.4g} Pa "
        f"= {p_out / p_in:.3g}: a gas or steam flow is sonic (choked) below about "
        f"{CHOKED_RATIO}, and the flow model (which grows with sqrt(p_in - p_out) without "
        "limit) no longer holds (a ControlValve models choking)"
    )


MAX_BALANCES = 50


def open_balances(system, t0, y, count=3) -> list[str]:
    """The balances furthest from rest at y: the equations with a derivative (mass,
    energy, a controller's integral) whose residual at y' = 0 moves their state the
    most, as the relative rate |F_i / (dF_i/dy'_j)| / scale_j [1/s] of the state y_j
    whose derivative they hold (scale_j = max(nominal_j, |y_j|))."""
    found = _balance_candidates(system, t0, y)
    if found is None:
        return []
    f, scale, rows = found
    rates = []
    # the rows that look largest with dF_i/dy'_j = 1 (a mass or energy balance), each
    # measured with one more evaluation: at most MAX_BALANCES of them
    for _, i, j in rows[:MAX_BALANCES]:
        yp = np.zeros(system.n)
        yp[j] = scale[j]
        try:
            c = (system.residual(t0, y, yp)[i] - f[i]) / scale[j]
        except (ResidualDomainError, DAEError, PlantError):
            continue
        if c != 0.0 and np.isfinite(c):
            rates.append((abs(f[i] / c) / scale[j], i, j, -f[i] / c))
    rates.sort(reverse=True)
    out = []
    for rate, i, j, dydt in rates[:count]:
        if rate <= 1e-9:
            break
        unit = system.units.get(system.names[j], "")
        unit = "" if unit in ("1", "-") else unit
        text = (
            f"{system.eq_names[i]} does not balance: {system.names[j]} = {y[j]:.4g} {unit} "
            f"would change at {dydt:.3g} {unit + '/s' if unit else 'per s'}".replace("  ", " ")
        )
        owner = system.var_owner[j]
        k = system.index.get(f"{owner}.p")
        if k is not None and system.units.get(system.names[k]) == "Pa":
            text += f" (its pressure {owner}.p = {y[k] / 1e5:.5g} bar)"
        out.append(text)
    return out


#: balances ``unclosed_balances`` tries (the ones furthest from rest where the search
#: stopped), and the relative change of the held state between its two solves [-]
MAX_UNCLOSED = 4
HOLD_STEP = 1e-2
#: a held state whose balance's rate changes by less than this fraction between the
#: two solves leaves the rate unchanged: a state free at rest [-]
FREE_RATE = 1e-3
#: the words of ``unclosed_balances``' sentences (``benchmarks/steady_start.py`` reads them)
UNCLOSED = "cannot close at rest"


def unclosed_balances(system, t0, y, stats, count=2, starts=None) -> list[str]:
    """Balances that close at rest by coincidence only, found at the state y where the
    search stopped: a state y_j whose value no other equation needs at rest (a drum's
    or tank's level when no flow and no controller reads it: its pressure follows
    from the mass balance alone, and the energy balance must close at that same
    pressure). Each candidate (the balances of ``open_balances``, furthest from rest
    first, ranked at y) is held at its value in the first of ``starts`` (default: y)
    from which it solves (``rest_newton`` with ``hold``; its derivative solved), the
    rest of the plant solved to rest, and again with y_j moved by
    HOLD_STEP of its scale: when both solves converge and the balance's rate
    dy_j/dt is the same in both (within FREE_RATE) and not zero, no value of y_j
    brings that balance to rest, and the plant has no state at rest near there.
    Returns a sentence per such balance (at most ``count``): the rate, the held
    state's owner's pressure, and for an energy balance [J] the power it misses."""
    rows = _balance_rows(system, t0, y)[:MAX_UNCLOSED]
    out = []
    for _, i, j in rows:
        if len(out) >= count:
            break
        found = _held_rates(system, t0, j, [y] if starts is None else starts, stats)
        if found is None:
            continue
        r0, r1, y1 = found
        if not abs(r0) / system.nominal[j] > 1e-12 or abs(r1 - r0) > FREE_RATE * abs(r0):
            continue
        unit = system.units.get(system.names[j], "")
        unit = "" if unit in ("1", "-") else unit
        per = f"{unit}/s" if unit else "per s"
        text = (
            f"{system.eq_names[i]} {UNCLOSED}: holding {system.names[j]} fixed, every other "
            "balance closes"
        )
        owner = system.var_owner[j]
        k = system.index.get(f"{owner}.p")
        if k is not None and system.units.get(system.names[k]) == "Pa":
            text += f" (at {owner}.p = {y1[k] / 1e5:.6g} bar)"
        text += f", and {system.names[j]} still changes at {r0:.6g} {per} whatever its value"
        if unit == "J":
            text += (
                f": the energy balance is {abs(r0) / 1e3:.6g} kW "
                f"{'short (less heat in than out)' if r0 < 0 else 'over (more heat in than out)'}"
            )
        elif unit == "kg":
            text += f": the mass balance is {abs(r0):.6g} kg/s {'short' if r0 < 0 else 'over'}"
        out.append(text)
    return out


def _held_rates(system, t0, j, starts, stats):
    """(rate, rate with y_j moved by HOLD_STEP of its scale, state at rest) of state j
    held (``unclosed_balances``), from the first of ``starts`` where both solves
    converge and the first lies inside the components' ranges (``range_problems``);
    None when none does. The modes are left as they were."""
    for start in starts:
        scale = max(float(system.nominal[j]), abs(float(start[j])))
        rates = []
        for shift in (0.0, HOLD_STEP):
            y0 = np.array(start, dtype=float)
            y0[j] += shift * scale
            modes = _save_modes(system)
            try:
                y1, yp1 = rest_newton(system, t0, y0, stats, hold=(j,))
            except (PlantError, DAEError, ResidualDomainError):
                break
            finally:
                _restore_modes(system, modes)
            if shift == 0.0 and range_problems(system, t0, y1):
                break  # a family outside the components' ranges (V_l > V_t) says nothing
            rates.append((float(yp1[j]), y1))
        if len(rates) == 2:
            return rates[0][0], rates[1][0], rates[0][1]
    return None


def _balance_candidates(system, t0, y):
    """(F at y' = 0, scale, rows) with rows the (relative rate, equation i, state j) of
    the balances with one derivative, of a non-accumulator state, largest |F_i| /
    scale_j first (scale_j = max(nominal_j, |y_j|)); None when F cannot be evaluated."""
    try:
        f = system.residual(t0, y, np.zeros(system.n))
    except (ResidualDomainError, DAEError, PlantError):
        return None
    pat = sp.csr_matrix(system.pattern_yp)
    scale = np.maximum(np.asarray(system.nominal, dtype=float), np.abs(y))
    rows = []
    for i in range(pat.shape[0]):
        cols = pat.indices[pat.indptr[i] : pat.indptr[i + 1]]
        if cols.size == 1 and not system.accumulator[cols[0]]:
            rows.append((abs(f[i]) / scale[cols[0]], i, int(cols[0])))
    return f, scale, sorted(rows, reverse=True)


def _balance_rows(system, t0, y) -> list[tuple[float, int, int]]:
    """The rows of ``_balance_candidates`` (``open_balances``' first ranking)."""
    found = _balance_candidates(system, t0, y)
    return [] if found is None else found[2]


def no_flow_problems(system, y, count=2) -> list[str]:
    """Flow-through components (inlet and outlet ports, one flow m) whose flow is below
    1e-3 of their nominal value at y, with the pressures at both ends: a pump against
    a pressure above its shut-off head, a check valve held shut."""
    out = []
    for name, comp in system.components.items():
        k = system.index.get(f"{name}.m")
        m_nom = comp.params.get("m_nominal") or 0.0
        if k is None or not m_nom or abs(y[k]) >= 1e-3 * m_nom:
            continue
        try:
            n_in = system.connections[(name, "inlet")]
            n_out = system.connections[(name, "outlet")]
        except KeyError:
            continue
        p_in, p_out = y[system.node_index[n_in]], y[system.node_index[n_out]]
        out.append(
            f"'{name}' ({type(comp).__name__}) passes {y[k]:.3g} kg/s (nominal {m_nom:g} "
            f"kg/s) from {p_in / 1e5:.5g} bar at '{n_in}' to {p_out / 1e5:.5g} bar at '{n_out}'"
        )
    return out[:count]
