"""Consistent values of an index-1 DAE F(t, y, y') = 0: one routine for every start.

``solve_consistent`` solves F(t, y, y') = 0 for a chosen set of unknowns: for
each component i either y_i (``y_unknown[i]``) or y'_i is unknown, the other is
kept. The cases in use:

- IDACalcIC's YA_YDP_INIT (start, tstops, events): y of the algebraic and y' of
  the differential components are unknown;
- a plant's steady start: every y unknown except the accumulators (running
  integrals), whose y' is solved for instead.

Unknowns and scales. With the weights w_i = 1 / (rtol |y_i| + atol_i),
recomputed from the *current* iterate at every iteration (a component that was
small at t0 must not get a round-off-level test later), an unknown y_i is
measured by w_i and an unknown y'_i by h w_i (h a time scale: a change d of y'
moves y by about h d over a step). ``uw`` below holds these unknown weights.

Newton. The Jacobian dF/du takes the columns of dF/dy for the y unknowns and of
dF/dy' for the y' unknowns; it is built by finite differences grouped by the
column colouring of ``linear_algebra.IterationMatrix`` (one residual per group of
columns that share no row) and factorised by its LU (banded where the pattern is).
It is kept while Newton contracts (modified Newton, as IDA's IDACalcIC): a fresh
Jacobian is taken at the start, after a step that needed backtracking, and when
a full step reduced the merit by less than RATE_REFRESH = 0.25; a kept Jacobian
whose full step does not descend is refreshed at the same point before any
backtracking. On the 36 plant files of plants/, tests/field/ and tests/plants/
this took 1.3 to 4 times fewer residual evaluations than a fresh Jacobian at
every iteration (benchmarks/README.md, "Start-up"). The Newton step d = -J^{-1} F is globalised by
backtracking: u + lam d is accepted when the merit function falls by the Armijo
factor (1 - 1e-4 lam), halving lam down to 1e-5. Two merit functions are tried in
turn, each from the starting values:

1. the natural-level function phi(u) = || J^{-1} F(u) ||_uw (the scaled Newton
   step, IDA's line search), affine invariant;
2. if that fails, the row-scaled residual psi(u) = || F(u) / r ||_2 with
   r_i = max_j |J_ij| / uw_j from the first Jacobian (each residual in tolerance
   units of the unknowns it sets).

Neither alone was enough for the plants: from a rough steady-start guess phi
stalled on superheater_line.toml where psi converged, and psi stalled on a steam
network (tests/field/steam_network_step.toml) where phi converged. phi is a
different function at every Jacobian; when the Jacobians change faster than
phi descends, its line search takes tiny steps (and phi at the next Jacobian may
be 100 times larger): after SHORT_STEPS_MAX = 4 iterations that needed lam below
1/64 the natural merit gives way to psi. superheater_line.toml reaches that at
iteration 16 (before, phi failed after 31 iterations and 28 Jacobians); of the
36 plant files in plants/, tests/field/ and tests/plants/ that phi solves, one
(tests/plants/pump_trip_check_valve.toml) needs 3 such iterations, none more.

Convergence when, at the current iterate,

- the scaled Newton step is small: ||d||_uw <= 0.01 * 0.33 (IDA's
  epicfac * epcon: a hundredth of the corrector's tolerance), or
- the step is at round-off: |d_j| <= 64 eps |u_j| for every j with
  |d_j| uw_j > 0.0033, i.e. no representable progress is left, or
- F is exactly zero.

A line search that cannot reduce the merit, or a Newton that runs out of
iterations, at a point already within the integrator's tolerance
(||d||_uw <= 1) is accepted too: the leftover is round-off of the property
functions, and the BDF corrector absorbs it. So is one whose residuals are all
below 1e-6 of the tolerance of the unknown each sets most, whatever ||d||_uw: in
a liquid volume the pressure follows from the mass M through the bulk modulus
K = rho/(drho/dp) ~ 2e9 Pa, so one ulp of M moves p by eps K ~ 5e-7 Pa, and the
flows of a low-friction line (0.1 Pa per volume at 1 kg/s) by ~2e-6 kg/s: more
than the tolerance of a flow at rtol 1e-7. The Newton step is then round-off
noise (||d||_uw ~ 4 on tests/field/closed_form_water.toml at its 5 s step, with
residuals at 7e-8 of the tolerance), no line search can reduce it, and the
integrator, which moves M as well, resolves the flows in its first step.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from dnasim.core.errors import DAEError, ResidualDomainError
from dnasim.solver.linear_algebra import SQRT_EPS, IterationMatrix, SingularMatrixError

EPS = float(np.finfo(float).eps)
MAX_ITERS = 30
TOLERANCE = 0.01 * 0.33  # IDA: epicfac * epcon
ROUNDOFF_STEP = 64.0 * EPS
LAMBDA_MIN = 1e-5
ARMIJO = 1e-4
WITHIN_TOLERANCE = 1.0
#: a stalled Newton is also accepted when every residual is below this fraction of
#: the tolerance of the unknown it sets most (``_scaled_residuals``): see the module doc
ROUNDOFF_RESIDUAL = 1e-6
#: a kept Jacobian is refreshed when a full Newton step reduces the merit by less
#: than this factor (modified Newton, ``_newton``)
RATE_REFRESH = 0.25
#: the natural merit gives way to the next one after SHORT_STEPS_MAX iterations whose
#: line search had to go below LAMBDA_SHORT (module doc)
LAMBDA_SHORT = 1.0 / 64.0
SHORT_STEPS_MAX = 4
#: the merit functions tried in turn, each from the starting values (module doc)
MERITS = ("natural", "residual")


def _evaluate(residual, t, y, yp):
    """F(t, y, yp), or None when it is outside its domain or not finite."""
    try:
        f = residual(t, y, yp)
    except ResidualDomainError:
        return None
    return f if np.all(np.isfinite(f)) else None


def _norm(v: np.ndarray) -> float:
    return float(np.sqrt(np.mean(v * v))) if v.size else 0.0


def var_name(names: Sequence[str] | None, i: int) -> str:
    """'water.flow' when names are known, else 'y[4]'."""
    if names is not None and i < len(names):
        return str(names[i])
    return f"y[{i}]"


def eq_name(names: Sequence[str] | None, i: int) -> str:
    """'water.mass' when names are known, else 'equation 4'."""
    if names is not None and i < len(names):
        return str(names[i])
    return f"equation {i}"


def solve_consistent(
    residual,
    t: float,
    y: np.ndarray,
    yp: np.ndarray,
    y_unknown: np.ndarray,
    *,
    rtol: float,
    atol: np.ndarray,
    h_scale: float,
    matrix: IterationMatrix,
    variable_names: Sequence[str] | None = None,
    equation_names: Sequence[str] | None = None,
    max_iters: int = MAX_ITERS,
    what: str = "the initial values",
) -> tuple[np.ndarray, np.ndarray]:
    """Return (y, yp) with F(t, y, yp) = 0, solved for y[y_unknown] and yp[~y_unknown].

    residual : F(t, y, yp) -> array (n,) (may raise ResidualDomainError).
    t : time [time unit of the problem]; y, yp : starting values (copied).
    y_unknown : boolean mask, True where y_i is unknown, False where y'_i is.
    rtol, atol : tolerances that define the weights 1 / (rtol |y| + atol).
    h_scale : time scale that turns a y' change into a y change [time unit].
    matrix : IterationMatrix of the residual (its colouring is used; its stored
        matrix is cleared afterwards, so the integrator builds its own).
    Raises DAEError naming the variables and equations on failure.
    """
    y = np.array(y, dtype=float)
    yp = np.array(yp, dtype=float)
    y_unknown = np.asarray(y_unknown, dtype=bool)
    ymask = y_unknown.astype(float)
    ypmask = 1.0 - ymask
    atol = np.broadcast_to(np.asarray(atol, dtype=float), y.shape)
    f = _evaluate(residual, t, y, yp)
    if f is None:
        raise DAEError(
            _message(
                t,
                what,
                "the residual cannot be evaluated (outside its domain or not finite) at the "
                "starting values",
                _nonfinite_equations(residual, t, y, yp, equation_names),
            )
        )
    y0, yp0, f0 = y, yp, f
    failures = []
    try:
        for merit in MERITS:
            ok, y, yp, f, scaled, uw, problem = _newton(
                residual,
                t,
                y0,
                yp0,
                f0,
                y_unknown,
                ymask,
                ypmask,
                rtol,
                atol,
                h_scale,
                matrix,
                max_iters,
                merit,
                what,
            )
            if ok:
                return y, yp
            failures.append((problem, f, scaled, uw, y, yp))
        # report the attempt that came closer
        problem, f, scaled, uw, y, yp = min(
            failures, key=lambda c: np.inf if c[2] is None else float(np.max(c[2], initial=0.0))
        )
        detail = _worst(f, scaled, uw, matrix, equation_names, variable_names)
    finally:
        matrix.matrix = None  # the integrator must build its own iteration matrix
    err = DAEError(
        _message(
            t, what, f"they are inconsistent and could not be made consistent ({problem})", detail
        )
    )
    err.state = (y, yp)  # the last Newton iterate, for the caller's diagnosis
    raise err


def _newton(
    residual,
    t,
    y,
    yp,
    f,
    y_unknown,
    ymask,
    ypmask,
    rtol,
    atol,
    h_scale,
    matrix,
    max_iters,
    merit,
    what,
):
    """Globalised Newton from (y, yp); returns (ok, y, yp, F, scaled residuals, uw, problem).

    merit "natural": backtracking on phi = ||J^{-1} F||_uw at the current Jacobian
    (IDA's line search); "residual": on psi = ||F / r||_2 with the row scales r of
    the first Jacobian (see the module doc). Raises DAEError for a singular Jacobian.

    Modified Newton (as IDA's IDACalcIC): the Jacobian and its LU are kept while the
    full step (lam = 1) reduces the merit by at least RATE_REFRESH; a step that needs
    backtracking, or contracts more slowly, gets a fresh Jacobian first, at the same
    point, so the line search and its failure are those of Newton with a current
    Jacobian. With the natural merit the kept matrix also keeps phi one function
    (||J0^{-1} F||), and the solve of the accepted trial is the next step.
    """
    scaled = None
    rows = None
    phi = np.inf
    uw = np.ones_like(y)
    jac = None  # the Jacobian in ``matrix``, kept while Newton contracts fast
    short_steps = 0  # iterations whose line search went below LAMBDA_SHORT
    d = None  # -J^{-1} F at the current point, when the line search computed it
    for _ in range(max_iters):
        if not np.any(f):
            return True, y, yp, f, scaled, uw, ""
        uw = 1.0 / (rtol * np.abs(y) + atol) * (ymask + h_scale * ypmask)
        u = np.where(y_unknown, y, yp)
        fresh = jac is None
        if fresh:
            try:
                jac = _jacobian(residual, t, y, yp, f, u, uw, ymask, ypmask, matrix)
            except ResidualDomainError as exc:
                # a finite-difference increment left the model's domain (a state at
                # IF97's limit): no Newton step from here, with the reason
                return False, y, yp, f, scaled, uw, f"the residual could not be evaluated: {exc}"
            d = None
            try:
                matrix.factorize()
            except SingularMatrixError as exc:
                err = DAEError(
                    _message(
                        t,
                        what,
                        "the Jacobian of F with respect to the unknowns (y of the algebraic, "
                        f"y' of the differential variables) is singular. {exc} If some "
                        "variables are algebraic (their derivatives appear nowhere), pass "
                        "them as `algebraic`",
                    )
                )
                err.state = (y, yp)  # where it failed, for the caller's diagnosis
                raise err from None
        scaled = _scaled_residuals(jac, f, uw)
        if d is None:
            d = matrix.solve(-f)
        dw = d * uw
        phi = _norm(dw)
        if not np.isfinite(phi):
            if not fresh:
                jac = None
                continue
            return False, y, yp, f, scaled, uw, "the Newton step is not finite"
        if phi <= TOLERANCE or _at_roundoff(d, dw, u):
            y, yp = _update(y, yp, d, 1.0, ymask, ypmask)
            return True, y, yp, f, scaled, uw, ""
        if merit == "residual":
            if rows is None:
                rows = _row_scales(jac, uw)
            before = float(np.linalg.norm(f / rows))
        else:
            before = phi
        lam = 1.0
        better = False
        while True:
            y_new, yp_new = _update(y, yp, d, lam, ymask, ypmask)
            f_new = _evaluate(residual, t, y_new, yp_new)
            if f_new is not None:
                if merit == "natural":
                    d_new = matrix.solve(-f_new)
                    after = _norm(d_new * uw)
                else:
                    after = float(np.linalg.norm(f_new / rows))
                better = after <= (1.0 - ARMIJO * lam) * before
                if better:
                    break
            if not fresh:
                break  # a kept Jacobian: take a fresh one here before any backtracking
            lam *= 0.5
            if lam < LAMBDA_MIN:
                break
        if not better and not fresh:
            jac = None
            continue
        if lam < LAMBDA_MIN:
            if _within_tolerance(phi, scaled):
                # Within the integrator's tolerance and no descent left: round-off.
                y, yp = _update(y, yp, d, 1.0, ymask, ypmask)
                return True, y, yp, f, scaled, uw, ""
            return False, y, yp, f, scaled, uw, "the line search could not reduce the residual"
        y, yp, f = y_new, yp_new, f_new
        short_steps += lam < LAMBDA_SHORT
        if merit == "natural" and short_steps >= SHORT_STEPS_MAX:
            if _within_tolerance(phi, scaled):
                # short steps at round-off (the residuals already far below the
                # tolerance), not a wandering merit: accepted as at the end
                return True, y, yp, f, scaled, uw, ""
            return False, y, yp, f, scaled, uw, "the line search stalled (short steps)"
        if lam < 1.0 or after > RATE_REFRESH * before:
            jac, d = None, None
        else:
            d = d_new if merit == "natural" else None
    if _within_tolerance(phi, scaled):
        # Newton creeps at the level of the property functions' round-off: the state
        # is consistent to within the integrator's tolerance, and its corrector
        # absorbs the rest.
        return True, y, yp, f, scaled, uw, ""
    return False, y, yp, f, scaled, uw, f"Newton did not converge in {max_iters} iterations"


def _within_tolerance(phi, scaled) -> bool:
    """A stalled Newton's iterate accepted (module doc): the step within the integrator's
    tolerance, or every residual below ROUNDOFF_RESIDUAL of its unknown's tolerance."""
    return phi <= WITHIN_TOLERANCE or (
        scaled is not None and np.max(scaled, initial=0.0) <= ROUNDOFF_RESIDUAL
    )


def _jacobian(residual, t, y, yp, f, u, uw, ymask, ypmask, matrix):
    """dF/du by finite differences; increments as IDA's: max(sqrt(eps) |u|, 1 / uw)."""
    inc = np.maximum(SQRT_EPS * np.abs(u), 1.0 / uw)
    inc = (u + inc) - u  # exactly representable
    tiny = inc == 0.0  # u so large that 1/uw is below its ulp
    if np.any(tiny):
        inc[tiny] = np.spacing(np.abs(u[tiny])) * 2.0**20
    jac = matrix.finite_difference(t, y, yp, f, inc, ymask, ypmask)
    matrix.matrix = jac
    matrix.cj = None
    return jac


def _row_scales(jac, uw) -> np.ndarray:
    """r_i = max_j |J_ij| / uw_j: F_i / r_i is residual i in tolerance units of the
    unknown it sets most (1 for an empty row)."""
    if hasattr(jac, "multiply"):
        r = np.asarray(abs(jac).multiply(1.0 / uw[None, :]).max(axis=1).todense()).ravel()
    else:
        r = np.max(np.abs(jac) / uw[None, :], axis=1) if jac.size else np.zeros(0)
    return np.where(np.isfinite(r) & (r > 0), r, 1.0)


def _update(y, yp, d, lam, ymask, ypmask):
    return y + lam * d * ymask, yp + lam * d * ypmask


def _at_roundoff(d, dw, u) -> bool:
    """No component can move by more than round-off where the step is not already small."""
    big = np.abs(dw) > TOLERANCE
    return bool(np.all(np.abs(d[big]) <= ROUNDOFF_STEP * np.abs(u[big])))


def _scaled_residuals(jac, f, uw) -> np.ndarray:
    """|F_i| / max_j |J_ij| / uw_j: each residual in tolerance units of the unknowns it sets."""
    return np.abs(f) / _row_scales(jac, uw)


def _worst(f, scaled, uw, matrix, equation_names, variable_names, count=4) -> str:
    """The largest residuals by name, largest first, with the unknown each one sets most."""
    if f is None:
        return ""
    measure = scaled if scaled is not None else np.abs(f)
    jac = matrix.matrix
    dense = None
    if jac is not None and f.size <= 5000:
        dense = np.abs(jac.toarray() if hasattr(jac, "toarray") else jac) / uw[None, :]
    parts = []
    for i in np.argsort(-measure)[:count]:
        if measure[i] == 0.0:
            continue
        text = f"{eq_name(equation_names, i)} (residual {f[i]:.3g}"
        if scaled is not None:
            text += f", {scaled[i]:.3g} times the tolerance"
        if dense is not None and np.any(dense[i]):
            text += f"; it sets mainly {var_name(variable_names, int(np.argmax(dense[i])))}"
        parts.append(text + ")")
    if not parts:
        return ""
    return "the largest remaining residuals, largest first: " + "; ".join(parts)


def _nonfinite_equations(residual, t, y, yp, equation_names) -> str:
    try:
        f = np.asarray(residual(t, y, yp), dtype=float)
    except ResidualDomainError as exc:
        return f"the residual reports: {exc}"
    bad = np.flatnonzero(~np.isfinite(f))[:5]
    if bad.size == 0:
        return ""
    return "NaN or inf in " + ", ".join(eq_name(equation_names, i) for i in bad)


def _message(t, what, problem, detail="") -> str:
    text = f"At t = {t:.10g}, {what}: {problem}"
    if detail:
        text += f"; {detail}"
    return text + "."


def detect_algebraic(residual, t, y, yp, matrix: IterationMatrix) -> np.ndarray:
    """Components whose derivative does not appear in F, found by probing dF/dy'.

    A column of dF/dy' that is zero at the initial point and at a perturbed point
    marks an algebraic component. A column that looks zero is probed again with
    increments 1e4, 1e8 and 1e12 times larger: when F holds terms far larger than
    the y' term (y' + 1e12 y, say), a small increment of y' is lost in round-off
    and the component would be taken for algebraic.
    """
    n = y.size
    mask = np.ones(n, dtype=bool)
    for scale in (1.0, 1.37):
        yp_probe = yp * scale + 1e-3 * (np.arange(n) % 7 + 1)
        f0 = residual(t, y, yp_probe)
        inc = 1e-6 * np.maximum(1.0, np.abs(yp_probe))
        inc = (yp_probe + inc) - yp_probe
        jac = matrix.finite_difference(t, y, yp_probe, f0, inc, 0.0, 1.0)
        dense = jac.toarray() if hasattr(jac, "toarray") else jac
        mask &= ~np.any(dense != 0.0, axis=0)
        for j in np.flatnonzero(mask):
            for factor in (1e4, 1e8, 1e12):
                probe = yp_probe.copy()
                probe[j] += factor * inc[j]
                try:
                    f1 = residual(t, y, probe)
                except ResidualDomainError:
                    mask[j] = False  # it depends on y'_j (its domain does)
                    break
                if np.any(f1 != f0):
                    mask[j] = False
                    break
    matrix.matrix = None
    return mask
