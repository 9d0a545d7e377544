"""Linearisation of a plant at an operating point: x' = A x + B u, y = C x + D u.

The plant is the semi-explicit index-1 DAE F(t, y, y', u) = 0 (``dnasim.compile(plant)``),
y = (x, z) with x the differential states (some equation holds x') and z the
algebraic variables. At a consistent point (t0, y0, y0', u0), with deviations
from it,

    E dx' + Jx dx + Jz dz + Fu du = 0,
    E = dF/dx' [-/s],  Jx = dF/dx,  Jz = dF/dz,  Fu = dF/du   (finite differences)

Index 1 means M = [E  Jz] (n x n) is nonsingular, so

    [dx'; dz] = -M^-1 (Jx dx + Fu du)  =>  A = -(M^-1 Jx)_x,  B = -(M^-1 Fu)_x,
                                           Zx = -(M^-1 Jx)_z,  Zu = -(M^-1 Fu)_z.

An output g(t, y, y') (any name of ``results.csv``: a variable, a node temperature,
a derived output) gives C = g_x + g_z Zx + g_x' A and D = g_z Zu + g_x' B.

Inputs (the documented hook, :func:`_input_hook`):

- ``component.parameter`` (``steam.T``): the parameter's value p(t) is replaced by
  p(t) + du while F is evaluated. Only parameters read in the residual count; one
  that a component precomputes in ``setup`` is reported as having no effect.
- ``component.variable`` or a linked signal input (``spray_valve.z``, resolved to
  the output it reads, ``pi.z``): the algebraic variable is held as an input; its
  defining equation (the first equation of its own component that contains it and
  leaves the algebraic block nonsingular) is replaced by ``z - (z0 + du) = 0``.
  This opens a control loop at that signal.

States that no output depends on, directly or through other states (the
boundaries' M_passed/H_passed counters, say), are dropped unless
``keep_all_states=True``: they add zero eigenvalues and make A singular.

Units: A [1/s] between states in their own SI units, B [state unit/(s input unit)],
C [output unit/state unit], D [output unit/input unit].

Control design from Python::

    import numpy as np
    import scipy.signal
    from dnasim.tools.linearize import linearize
    from dnasim.plant.plantfile import load

    lm = linearize(load("plants/attemperator.toml"), ["spray_valve.z"], ["sensor.T_s"])
    w = np.logspace(-3, 2, 200)                 # [rad/s]
    G = lm.frequency_response(w)[:, 0, 0]       # K per unit opening
    t, y = scipy.signal.step(lm.to_statespace(), T=np.linspace(0, 60, 601))
    print(lm.eigenvalues, lm.dc_gain)           # poles [1/s], static gains [K/-]
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp

__all__ = ["LinearModel", "linearize", "LinearizeError"]

from dnasim.core.errors import DnasimError


class LinearizeError(DnasimError, ValueError):
    """A linearisation that cannot be done (unknown input, singular algebraic block)."""


# --------------------------------------------------------------------------- adapters
# The only places that touch the plant: re-point these at a new pipeline.


def _plant_of(plant_or_loaded):
    """The ``Plant`` and the ``SimulationSettings`` (or None) of a plant or LoadedPlant."""
    if hasattr(plant_or_loaded, "plant") and hasattr(plant_or_loaded, "simulation"):
        return plant_or_loaded.plant, plant_or_loaded.simulation
    return plant_or_loaded, None


def _operating_point(system, sim, t):
    """Consistent (t, y, y') where to linearise: steady start at t0 (``t=None``) or
    the simulated state at time ``t`` (integrated from the file's start)."""
    t0 = sim.t_start if sim is not None else 0.0
    start = sim.start if sim is not None else "steady"
    from dnasim.start.initial import initial_values

    if t is None or t == t0:
        y, yp = initial_values(system, t0, "steady" if t is None else start)
        return t0, y, yp
    from dnasim.solver import solve_dae

    dae = system
    y0, yp0 = initial_values(system, t0, start)
    last = {}

    def keep(tt, y, yp):
        last["p"] = (float(tt), np.array(y), np.array(yp))

    rtol = sim.rtol if sim is not None else 1e-6
    atol = sim.atol_scaled if sim is not None else 1e-6
    solve_dae(
        dae.residual,
        (t0, float(t)),
        y0,
        yp0,
        algebraic=dae.algebraic,
        quadrature=dae.quadrature,
        jac_sparsity=dae.jac_sparsity,
        residual_for_columns=getattr(dae, "residual_for_columns", None),
        calc_initial=False,
        rtol=rtol,
        atol=dae.atol_vector(atol, y0),
        events=dae.events,
        tstops=dae.tstops(t0, float(t)),
        callback=keep,
        throw=True,
    )
    return last["p"]


def _output_function(system):
    names = list(system.output_names())
    units = dict(system.output_units())
    return names, units, system.output_row


# --------------------------------------------------------------------------- inputs


class _ParamInput:
    def __init__(self, comp, name, unit):
        self.comp, self.name, self.unit = comp, name, unit
        self.original = comp.params[name]

    def value(self, t):
        return float(self.comp.param_at(self.name, t))

    def set(self, du):
        f = self.original
        if du == 0.0:
            self.comp.params[self.name] = f
        elif callable(f):
            self.comp.params[self.name] = lambda t, f=f, du=du: f(t) + du
        else:
            self.comp.params[self.name] = f + du

    def restore(self):
        self.comp.params[self.name] = self.original


def _input_hook(plant, dae, ref):
    """("param", _ParamInput) or ("variable", global index) for an input name."""
    if ref.count(".") != 1:
        raise LinearizeError(f"input {ref!r}: expected 'component.parameter' or 'component.signal'")
    cname, pname = ref.split(".")
    comp = plant.components.get(cname)
    if comp is None:
        raise LinearizeError(f"input {ref!r}: no component named '{cname}'")
    link = getattr(plant, "links", {}).get((cname, pname))
    if link is not None:
        ref = f"{link[0]}.{link[1]}"
        src = plant.components.get(link[0])  # None: a node's p or h ("n_hdr.p")
        outs = src.signal_outputs() if src is not None else ()
        port = next((p for p in outs if p.name == link[1]), None)
        if port is not None and getattr(port, "variable", None):
            ref = f"{link[0]}.{port.variable}"
    if ref in dae.index:
        k = dae.index[ref]
        if not dae.algebraic[k]:
            raise LinearizeError(
                f"input {ref!r} is a differential state; only algebraic variables (signals, "
                "flows, ...) and parameters can be held as inputs"
            )
        return "variable", k
    params = {p.name: p for p in comp.PARAMS}
    if pname in params and params[pname].kind == "number":
        if comp.params.get(pname) is None:
            raise LinearizeError(f"input {ref!r}: the parameter is not set in this plant")
        return "param", _ParamInput(comp, pname, params[pname].unit)
    raise LinearizeError(
        f"input {ref!r}: '{pname}' is neither a numeric parameter nor a variable or signal "
        f"input of component '{cname}' ({type(comp).__name__})"
    )


def _defining_row(dae, k, M_of):
    """The equation replaced by 'z_k = u': rows of the variable's own component that
    contain it, first the one that keeps the algebraic block nonsingular."""
    col = dae.jac_sparsity.tocsc()[:, k]
    rows = list(col.nonzero()[0])
    owner = dae.var_owner[k] if hasattr(dae, "var_owner") else None
    own = [r for r in rows if getattr(dae, "eq_owner", [None] * dae.n_equations)[r] == owner]
    for r in own + [r for r in rows if r not in own]:
        if _nonsingular(M_of(r)):
            return r
    raise LinearizeError(
        f"input {dae.names[k]!r}: no equation can be replaced by 'held as input' "
        "without making the algebraic block singular"
    )


def _nonsingular(M) -> bool:
    """Numerically nonsingular after equilibration (rows, then columns, to max 1)."""
    M = np.asarray(M, dtype=float)
    r = np.abs(M).max(axis=1)
    if (r == 0).any():
        return False
    M = M / r[:, None]
    c = np.abs(M).max(axis=0)
    if (c == 0).any():
        return False
    return bool(np.linalg.cond(M / c[None, :]) < 1e12)


# --------------------------------------------------------------------------- model


@dataclass
class LinearModel:
    """x' = A x + B u, y = C x + D u (deviations from the operating point)."""

    A: sp.csr_matrix
    B: sp.csr_matrix
    C: sp.csr_matrix
    D: sp.csr_matrix
    state_names: list[str]
    state_units: list[str]
    input_names: list[str]
    input_units: list[str]
    output_names: list[str]
    output_units: list[str]
    t: float
    x0: np.ndarray
    u0: np.ndarray
    y0: np.ndarray
    dropped_states: list[str] = field(default_factory=list)

    @property
    def eigenvalues(self) -> np.ndarray:
        """Poles of A [1/s], sorted by real part (slowest first)."""
        if self.A.shape[0] == 0:
            return np.empty(0, dtype=complex)
        ev = np.linalg.eigvals(self.A.toarray())
        return ev[np.argsort(-ev.real)]

    @property
    def time_constants(self) -> np.ndarray:
        """-1/Re(lambda) [s] per eigenvalue (inf for Re = 0)."""
        re = self.eigenvalues.real
        with np.errstate(divide="ignore"):
            return np.where(re != 0, -1.0 / re, np.inf)

    @property
    def damping(self) -> np.ndarray:
        """Damping ratio -Re(lambda)/|lambda| per eigenvalue [-] (1 for real poles)."""
        ev = self.eigenvalues
        mag = np.abs(ev)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(mag > 0, -ev.real / mag, 1.0)

    @property
    def dc_gain(self) -> np.ndarray:
        """Static gains D - C A^-1 B [output unit/input unit]; nan when A is singular."""
        A = self.A.toarray()
        if A.shape[0] == 0:
            return self.D.toarray()
        ev = np.abs(self.eigenvalues)
        if ev.min() <= 1e-10 * ev.max():  # an integrator: no static gain
            return np.full(self.D.shape, np.nan)
        X = np.linalg.solve(A, self.B.toarray())
        return self.D.toarray() - self.C.toarray() @ X

    def frequency_response(self, w) -> np.ndarray:
        """G(jw) = C (jw I - A)^-1 B + D at the angular frequencies ``w`` [rad/s],
        shape (len(w), outputs, inputs), solved on the state space directly (a
        transfer-function polynomial of a stiff plant is badly conditioned)."""
        A, B, C, D = (m.toarray() for m in (self.A, self.B, self.C, self.D))
        eye = np.eye(A.shape[0])
        return np.array([C @ np.linalg.solve(1j * wk * eye - A, B) + D for wk in np.atleast_1d(w)])

    def to_statespace(self):
        """A ``scipy.signal.StateSpace`` (dense matrices) for control design."""
        import scipy.signal

        return scipy.signal.StateSpace(
            self.A.toarray(), self.B.toarray(), self.C.toarray(), self.D.toarray()
        )

    def _arrays(self) -> dict:
        return {
            "A": self.A.toarray(),
            "B": self.B.toarray(),
            "C": self.C.toarray(),
            "D": self.D.toarray(),
            "state_names": np.array(self.state_names, dtype=object),
            "state_units": np.array(self.state_units, dtype=object),
            "input_names": np.array(self.input_names, dtype=object),
            "input_units": np.array(self.input_units, dtype=object),
            "output_names": np.array(self.output_names, dtype=object),
            "output_units": np.array(self.output_units, dtype=object),
            "t": self.t,
            "x0": self.x0,
            "u0": self.u0,
            "y0": self.y0,
            "eigenvalues": self.eigenvalues,
            "dc_gain": self.dc_gain,
        }

    def save_npz(self, path) -> Path:
        """A, B, C, D as scipy.sparse ``.npz`` files next to ``path`` (``path`` itself holds
        the names, units, operating point, eigenvalues and DC gains, as str arrays)."""
        path = Path(path)
        base = path.with_suffix("")
        for k in "ABCD":
            sp.save_npz(f"{base}_{k}.npz", getattr(self, k).tocsr())
        arrs = self._arrays()
        for k in "ABCD":
            arrs.pop(k)
        np.savez(
            path,
            **{
                k: (v.astype(str) if getattr(v, "dtype", None) is np.dtype(object) else v)
                for k, v in arrs.items()
            },
        )
        return path

    def save_mat(self, path) -> Path:
        """All of it in one MATLAB ``.mat`` file (sparse A, B, C, D; cell arrays of names)."""
        import scipy.io

        arrs = self._arrays()
        for k in "ABCD":
            arrs[k] = getattr(self, k).tocsc()
        scipy.io.savemat(str(path), arrs)
        return Path(path)

    def summary(self) -> str:
        lines = [
            f"linear model at t = {self.t:g} s: {len(self.state_names)} states, "
            f"{len(self.input_names)} inputs, {len(self.output_names)} outputs"
        ]
        if self.dropped_states:
            lines.append(f"dropped {len(self.dropped_states)} states no output depends on")
        lines.append("")
        lines.append(f"{'eigenvalue [1/s]':>28}  {'time constant [s]':>17}  {'damping':>7}")
        for ev, tc, z in zip(self.eigenvalues, self.time_constants, self.damping, strict=True):
            evs = f"{ev.real:.6g}" + (f" {ev.imag:+.6g}j" if ev.imag != 0 else "")
            lines.append(f"{evs:>28}  {tc:>17.6g}  {z:>7.3f}")
        lines.append("")
        lines.append("DC gains (output / input):")
        G = self.dc_gain
        for i, (yn, yu) in enumerate(zip(self.output_names, self.output_units, strict=True)):
            for j, (un, uu) in enumerate(zip(self.input_names, self.input_units, strict=True)):
                lines.append(f"  {yn} / {un}: {G[i, j]:.6g} [{yu or '-'}/{uu or '-'}]")
        return "\n".join(lines)


# --------------------------------------------------------------------------- linearize


def _fd_columns(f, x0, idx, scale, f0):
    """Forward differences of f at x0 in the coordinates ``idx`` -> dense (len(f0), len(idx))."""
    out = np.zeros((len(f0), len(idx)))
    sq = np.sqrt(np.finfo(float).eps)
    for j, k in enumerate(idx):
        h = sq * max(abs(x0[k]), scale[k])
        x = x0.copy()
        x[k] += h
        h = x[k] - x0[k]
        out[:, j] = (f(x) - f0) / h
    return out


def linearize(
    plant_or_loaded,
    inputs,
    outputs,
    t: float | None = None,
    *,
    keep_all_states: bool = False,
) -> LinearModel:
    """Linear model of a plant (or ``LoadedPlant``) around its steady state
    (``t=None``) or its simulated state at time ``t`` [s]. See the module docstring
    for the method, the input hook and the units."""
    plant, sim = _plant_of(plant_or_loaded)
    inputs = [inputs] if isinstance(inputs, str) else list(inputs)
    outputs = [outputs] if isinstance(outputs, str) else list(outputs)
    dae = plant = plant.compile()  # the System: components, links, residual, outputs
    out_names, out_units, out_row = _output_function(dae)
    missing = [o for o in outputs if o not in out_names]
    if missing:
        raise LinearizeError(
            f"output(s) {', '.join(missing)} not among the plant's results; e.g. "
            + ", ".join(out_names[:12])
        )
    hooks = [_input_hook(plant, dae, u) for u in inputs]
    try:
        t0, y0, yp0 = _operating_point(plant, sim, t)
    except DnasimError as exc:
        where = "the steady state" if t is None else f"the state at t = {t:g} s"
        hint = " (a later time, t=T or --at T, may help)" if t is None else ""
        raise LinearizeError(f"cannot find {where} to linearise at{hint}: {exc}") from None
    n = dae.n
    scale = np.maximum(np.asarray(dae.nominal, dtype=float), 1e-8)
    held = {}  # equation row -> (variable index, input number)
    u0 = np.zeros(len(inputs))
    u_units = []
    for j, (kind, h) in enumerate(hooks):
        if kind == "param":
            u0[j] = h.value(t0)
            u_units.append(h.unit)
        else:
            u0[j] = y0[h]
            u_units.append(dae.units.get(dae.names[h], ""))

    diff = np.flatnonzero(~dae.algebraic)
    alg = np.flatnonzero(dae.algebraic)
    u_now = u0.copy()

    def F(y, yp):
        r = np.asarray(dae.residual(t0, y, yp), dtype=float).copy()
        for row, (k, j) in held.items():
            r[row] = (y[k] - u_now[j]) / scale[k]
        return r

    def F_u(u):
        u_now[:] = u
        try:
            for j, (kind, h) in enumerate(hooks):
                if kind == "param":
                    h.set(u[j] - u0[j])
            return F(y0, yp0)
        finally:
            for kind, h in hooks:
                if kind == "param":
                    h.restore()
            u_now[:] = u0

    try:
        F0 = F(y0, yp0)
        Jy = _fd_columns(lambda y: F(y, yp0), y0, range(n), scale, F0)
        Jyp = _fd_columns(lambda yp: F(y0, yp), yp0, diff, scale / 1.0, F0)
        for j, (kind, h) in enumerate(hooks):
            if kind == "variable":

                def M_of(row, k=h):
                    Jm = Jy.copy()
                    Jm[row, :] = 0.0
                    Jm[row, k] = 1.0 / scale[k]
                    Mm = np.zeros((n, n))
                    Mm[:, : len(diff)] = Jyp
                    Mm[row, : len(diff)] = 0.0  # the replaced row has no derivative left
                    Mm[:, len(diff) :] = Jm[:, alg]
                    return Mm

                row = _defining_row(dae, h, M_of)
                held[row] = (h, j)
        if held:
            F0 = F(y0, yp0)
            Jy = _fd_columns(lambda y: F(y, yp0), y0, range(n), scale, F0)
            Jyp = _fd_columns(lambda yp: F(y0, yp), yp0, diff, scale, F0)
        uscale = np.maximum(np.abs(u0), 1e-3)
        Fu = _fd_columns(F_u, u0, range(len(u0)), uscale, F0)
        if len(inputs) and not np.any(Fu, axis=0).all():
            dead = [inputs[j] for j in range(len(inputs)) if not np.any(Fu[:, j])]
            raise LinearizeError(
                f"input(s) {', '.join(dead)} do not change any equation at the operating "
                "point (a parameter precomputed in the component's setup?)"
            )
    finally:
        for kind, h in hooks:
            if kind == "param":
                h.restore()

    M = np.hstack([Jyp, Jy[:, alg]])
    if not _nonsingular(M):
        raise LinearizeError(
            "the matrix [dF/dx', dF/dz] is singular at the operating point: the algebraic "
            "block is not of index 1 there"
        )
    lu = sp.linalg.splu(sp.csc_matrix(M))
    nd = len(diff)
    Sx = -lu.solve(Jy[:, diff])
    Su = -lu.solve(Fu) if len(inputs) else np.zeros((n, 0))
    A, Zx = Sx[:nd], Sx[nd:]
    B, Zu = Su[:nd], Su[nd:]

    # outputs: g(t, y, y') by finite differences in y and in x'
    sel = [out_names.index(o) for o in outputs]

    def g_y(y):
        return np.asarray(out_row(t0, y, yp0), dtype=float)[sel]

    def g_yp(yp):
        return np.asarray(out_row(t0, y0, yp), dtype=float)[sel]

    g0 = g_y(y0)
    Gy = _fd_columns(g_y, y0, range(n), scale, g0)
    Gyp = _fd_columns(g_yp, yp0, diff, scale, g0)
    C = Gy[:, diff] + Gy[:, alg] @ Zx + Gyp @ A
    D = Gy[:, alg] @ Zu + Gyp @ B

    # drop the states no output depends on (directly or through A)
    keep = np.ones(nd, dtype=bool)
    if not keep_all_states and nd:
        # structural: finite differences give exact zeros where nothing depends (a
        # threshold would cut real couplings between states of very different units)
        reach = (C != 0).any(axis=0)
        dep = A != 0
        while True:
            new = reach | dep[reach, :].any(axis=0)
            if (new == reach).all():
                break
            reach = new
        keep = reach
    names = [dae.names[i] for i in diff]
    units = [dae.units.get(nm, "") for nm in names]
    k = np.flatnonzero(keep)

    def csr(a):
        a = np.where(np.abs(a) > 0, a, 0.0)
        return sp.csr_matrix(a)

    return LinearModel(
        A=csr(A[np.ix_(k, k)]),
        B=csr(B[k]),
        C=csr(C[:, k]),
        D=csr(D),
        state_names=[names[i] for i in k],
        state_units=[units[i] for i in k],
        input_names=inputs,
        input_units=u_units,
        output_names=outputs,
        output_units=[out_units.get(o, "") for o in outputs],
        t=float(t0),
        x0=y0[diff][k],
        u0=u0,
        y0=g0,
        dropped_states=[names[i] for i in np.flatnonzero(~keep)],
    )
