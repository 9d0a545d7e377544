"""Switch functions: detecting their sign changes and locating them.

A switch function g(t, y, y') (seed sec. 10.2.1) is defined to change sign at a
discontinuity. After every accepted step the driver compares the signs of g at
the two ends of the step. On a change, the zero is located on the step's
Nordsieck interpolant by iterating on the inverse function t = g^{-1}(0):
inverse quadratic interpolation through the last three iterates (secant when
only two are distinct), safeguarded by bisection so it can never stall
(Brent's zeroin). It stops when the bracket is a few ulp of t wide or g is
exactly zero, and returns the bracket end on the *new* side of the switch, so
that integration restarts where the switch has already changed sign (seed:
"it is important that the method is restarted at a time instance where the
switch has changed its sign"). Every iterate (t, g) is recorded.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from dnasim.core.errors import DAEError
from dnasim.solver.callbacks import call_user

EPS = float(np.finfo(float).eps)
MAX_ITERATIONS = 100


@dataclass
class SwitchFunction:
    """A user's switch function, scalar or vector, with its attributes made explicit.

    Scalar: g(t, y, yp) -> float, with optional ``direction`` (-1, 0, +1),
    ``terminal``, ``restart``, ``action(t, y, yp)`` and ``name``.

    Vector: an object with an integer attribute ``size``; g(t, y, yp) -> array of
    shape (size,); ``direction`` a scalar or an array of -1/0/+1 per element,
    ``names`` (size strings), ``terminal``, ``restart`` and an optional
    ``action(t, y, yp, which)`` with ``which`` the int array of the elements that
    crossed at the located time.

    ``kink = True`` (with ``restart``): g marks a kink of the residual (a phase
    line). The solver then takes its finite differences on the side of g where the
    point lies and cuts a step that failed in Newton at the crossing predicted on
    the last step's polynomial (``linear_algebra``, ``bdf``).

    ``rearm = True`` (with an action): the action makes g positive again (a mode
    toggle: the new mode has its own g); see ``missed``.

    A switch *restarts* (cut the step at the crossing, make consistent, restart
    at order 1) when it is terminal, has an action, or has ``restart = True``;
    otherwise it only observes (its crossings are located and logged).
    """

    g: Callable
    index: int
    name: str
    direction: np.ndarray  # per element: +1 only rising (- to +), -1 only falling, 0 both
    terminal: bool
    action: Callable | None
    size: int = 1
    vector: bool = False
    names: list = field(default_factory=list)
    restart_only: bool = False
    kink: bool = False
    rearm: bool = False
    #: per element: at or past its zero since the start (``arm``), or None
    armed: np.ndarray | None = None

    @classmethod
    def wrap(cls, g, index) -> SwitchFunction:
        if not callable(g):
            raise DAEError(f"events[{index}] is not callable; a switch function is g(t, y, yp).")
        name = getattr(g, "name", None) or getattr(g, "__name__", None) or f"event{index}"
        name = str(name)
        size = getattr(g, "size", None)
        vector = size is not None
        if vector:
            if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < 1:
                raise DAEError(
                    f"events[{index}] ({name!r}).size must be a positive integer; got {size!r}."
                )
            size = int(size)
        else:
            size = 1
        try:
            direction = np.sign(
                np.broadcast_to(
                    np.asarray(_or_zero(getattr(g, "direction", None)), dtype=float), (size,)
                )
            ).astype(int)
        except (TypeError, ValueError):
            raise DAEError(
                f"events[{index}] ({name!r}).direction must be -1, 0, 1 or {size} such values."
            ) from None
        names = getattr(g, "names", None)
        if vector:
            if names is None:
                names = [f"{name}[{j}]" for j in range(size)]
            names = [str(v) for v in names]
            if len(names) != size:
                raise DAEError(
                    f"events[{index}] ({name!r}) has size {size} but {len(names)} names."
                )
        else:
            names = [name]
        action = getattr(g, "action", None)
        if action is not None and not callable(action):
            raise DAEError(f"events[{index}].action is not callable.")
        return cls(
            g,
            index,
            name,
            direction,
            bool(getattr(g, "terminal", False)),
            action,
            size,
            vector,
            names,
            bool(getattr(g, "restart", False)),
            bool(getattr(g, "kink", False)),
            bool(getattr(g, "rearm", False)),
        )

    @property
    def restarts(self) -> bool:
        """Cut the step at a crossing and restart at order 1 there."""
        return self.terminal or self.action is not None or self.restart_only

    def value(self, t, y, yp) -> np.ndarray:
        """g(t, y, yp) as an array of shape (size,) (one call of the user's function)."""
        v = call_user(self.g, f"the switch function {self.name!r}", t, t, y, yp)
        try:
            v = np.asarray(v, dtype=float)
        except (TypeError, ValueError):
            raise DAEError(
                f"Switch function {self.name!r} returned {v!r}; it must return "
                + (f"{self.size} numbers." if self.vector else "one number.")
            ) from None
        if v.size != self.size or (self.vector and v.ndim > 1):
            raise DAEError(
                f"Switch function {self.name!r} returned shape {v.shape}; it must return "
                + (f"shape ({self.size},)." if self.vector else "one number.")
            )
        v = v.reshape(self.size)
        if not np.all(np.isfinite(v)):
            bad = int(np.flatnonzero(~np.isfinite(v))[0])
            raise DAEError(
                f"Switch function {self.names[bad]!r} returned {v[bad]} at t = {t:.10g}."
            )
        return v

    def crossed(self, g_old: np.ndarray, g_new: np.ndarray) -> np.ndarray:
        """Per element: a sign change from g_old to g_new that its direction reports,
        or a missed one (``missed``).

        No change when g_old is exactly 0 (it left the switch) or g_new is exactly 0
        (not across yet; seen on the next step).
        """
        change = (g_old != 0.0) & (g_new != 0.0) & (np.sign(g_old) != np.sign(g_new))
        rising = g_new > 0.0
        wanted = (self.direction == 0) | ((self.direction > 0) == rising)
        return (change & wanted) | self.missed(g_old, g_new)

    def arm(self, g: np.ndarray) -> None:
        """The rule of the start (t0): an element of a directed switch that changes a mode
        or stops the run (an action, or terminal) whose g is exactly zero at t0, or
        already on the side its direction reports, takes the mode the dynamics demand.
        It is *armed*: when the trajectory moves it further to the reported side (the
        next steps' g, see ``missed``), it crossed at the start of that step, and the
        switch acts there (at t0 when the first step moves it); when it moves to the
        other side (g strictly on the side of the current mode), it is disarmed and
        seen as any other element from then on.

        Why: without it an element that starts at g = 0 never changes sign (``crossed``
        needs g_old != 0), so a limit that starts exactly at its switching point is never
        engaged. Measured on the Modelica Standard Library's Fluid.Examples.DrumBoiler
        (plants/msl_drum_boiler.toml): its feed limiter starts at its lower limit 0 with
        the level rising, and the feed flow went to -4.7 kg/s (water drawn out of the
        drum) for 760 s, 1.4 bar off MSL's reference result.

        The first derivative of g does not decide (that drum starts at rest: the heat
        ramps from 0, so dg/dt = 0 at t0 and the second derivative moves it); the
        steps do, as many as it takes g to leave zero."""
        if not (self.terminal or self.action is not None):
            self.armed = None
            return
        g = np.asarray(g, dtype=float).reshape(self.size)
        armed = (self.direction != 0) & (-self.direction * g <= 0.0)
        self.armed = armed if armed.any() else None

    def keep_armed(self, g: np.ndarray) -> None:
        """Disarm the elements that ``g`` puts strictly on the side of their mode."""
        if self.armed is None:
            return
        g = np.asarray(g, dtype=float).reshape(self.size)
        armed = self.armed & (-self.direction * g <= 0.0)
        self.armed = armed if armed.any() else None

    def missed(self, g_old: np.ndarray, g_new: np.ndarray) -> np.ndarray:
        """Per element of a directed, re-arming switch (``rearm``), or an element armed at
        the start (``arm``): g_old already on (or at) the side its direction reports, and
        g_new further on it. Such an element crossed at the start of the step, where its
        sign was lost.

        It happens after a restart: the crossing is located on the step's interpolant,
        whose algebraic unknowns (a volume's h, say) are not exactly consistent with its
        differential ones (M, U) between the step's ends, and the consistent state after
        the action may sit a little past the line of the new mode. Measured on
        tests/field/condensing_pipe.toml: a volume switched to two-phase landed 1.2e-10
        J/kg on the liquid side of h', g_old = -1.2e-10; with a sign change required the
        crossing back was never seen and the volume stayed on the two-phase branch 300
        kJ/kg below the line, its mass growing to 138 kg in 2.5 L, exit 0.
        Moving away from zero (not back towards it, as a PI controller's output that
        reached its limit exactly does) is what marks it."""
        rearming = self.action is not None and self.rearm
        if not rearming and self.armed is None:
            return np.zeros(np.shape(g_new), dtype=bool)
        d = np.broadcast_to(self.direction, np.shape(g_new))
        down = (d < 0) & (g_old <= 0.0) & (g_new < g_old)
        up = (d > 0) & (g_old >= 0.0) & (g_new > g_old)
        if rearming:
            return down | up
        return (down | up) & np.broadcast_to(self.armed, np.shape(g_new))


def _or_zero(v):
    return 0 if v is None else v


def locate_zero(
    g: Callable[[float], float], t_a: float, g_a: float, t_b: float, g_b: float
) -> tuple[float, float, list[tuple[float, float]], float]:
    """Zero of g between t_a (old sign) and t_b (new sign), by Brent's zeroin.

    Returns (t_star, g(t_star), iterates, t_old) with t_star on the new side of
    the switch (sign of g_b, or g = 0), within a few ulp of the true crossing, and
    t_old the other end of the final bracket (old side).
    """
    iterates = [(t_a, g_a), (t_b, g_b)]
    new_sign = np.sign(g_b)
    a, fa, b, fb = t_a, g_a, t_b, g_b
    c, fc = a, fa
    d = e = b - a
    for _ in range(MAX_ITERATIONS):
        if np.sign(fb) == np.sign(fc):
            c, fc = a, fa
            d = e = b - a
        if abs(fc) < abs(fb):
            a, fa = b, fb
            b, fb = c, fc
            c, fc = a, fa
        tol = 2.0 * EPS * abs(b)
        m = 0.5 * (c - b)
        if abs(m) <= tol or fb == 0.0:
            break
        if abs(e) >= tol and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:  # secant
                p = 2.0 * m * s
                qq = 1.0 - s
            else:  # inverse quadratic interpolation
                qq = fa / fc
                r = fb / fc
                p = s * (2.0 * m * qq * (qq - r) - (b - a) * (r - 1.0))
                qq = (qq - 1.0) * (r - 1.0) * (s - 1.0)
            if p > 0.0:
                qq = -qq
            else:
                p = -p
            if 2.0 * p < min(3.0 * m * qq - abs(tol * qq), abs(e * qq)):
                e, d = d, p / qq
            else:
                d = e = m
        else:
            d = e = m
        a, fa = b, fb
        b = b + d if abs(d) > tol else b + np.copysign(tol, m)
        fb = g(b)
        iterates.append((b, fb))
    # The bracket is [b, c] (or b is an exact zero). Return its end on the new side.
    if fb == 0.0 or np.sign(fb) == new_sign:
        return b, fb, iterates, c
    if fc == 0.0 or np.sign(fc) == new_sign:
        if (c, fc) != iterates[-1]:
            iterates.append((c, fc))
        return c, fc, iterates, b
    raise DAEError("internal error: the switch-function bracket was lost")  # pragma: no cover


def locate_earliest(
    values: Callable[[float], np.ndarray],
    sw: SwitchFunction,
    t_a: float,
    g_a: np.ndarray,
    t_b: float,
    g_b: np.ndarray,
) -> tuple[float, np.ndarray, np.ndarray, int, list]:
    """The earliest crossing of a (vector) switch in (t_a, t_b].

    ``values(t)`` returns the whole vector g at t on the step's interpolant (one
    call of the user's function). Only elements that changed sign are bracketed:
    the one whose linear interpolation crosses first is located by
    ``locate_zero``; if another element has already crossed at the old-side end
    of the final bracket, the search repeats on the shorter interval.

    Returns (t_star, g(t_star), which, located element, iterates of that element),
    ``which`` the elements that crossed between t_a and t_star.
    """
    missed = np.flatnonzero(sw.missed(g_a, g_b))
    if missed.size:
        # crossed where the step began (see SwitchFunction.missed): act there
        k = int(missed[0])
        return t_a, g_a, missed, k, [(t_a, float(g_a[k]))]
    while True:
        candidates = np.flatnonzero(sw.crossed(g_a, g_b))
        ga, gb = g_a[candidates], g_b[candidates]
        frac = ga / (ga - gb)
        k = int(candidates[np.argmin(frac)])
        cache: dict[float, np.ndarray] = {}

        def scalar(t, k=k, cache=cache):
            if t not in cache:
                cache[t] = values(t)
            return float(cache[t][k])

        t_star, _, iterates, _ = locate_zero(scalar, t_a, g_a[k], t_b, g_b[k])
        # The old-side end of the final bracket: the latest iterate before t_star whose
        # value still has the old sign.
        old_sign = np.sign(g_a[k])
        t_old = max((t for t, v in iterates if t < t_star and np.sign(v) == old_sign), default=t_a)
        g_star = cache[t_star] if t_star in cache else (g_b if t_star == t_b else values(t_star))
        if t_old == t_a:
            g_old = g_a
        else:
            g_old = cache[t_old] if t_old in cache else values(t_old)
        earlier = sw.crossed(g_a, g_old)
        if t_old != t_a and np.any(earlier):
            t_b, g_b = t_old, g_old  # another element crossed before this bracket
            continue
        # Crossed by t_star: a sign change, or (for elements that change sign in the
        # step) exactly zero there, like the located one may be.
        at_zero = candidates[g_star[candidates] == 0.0]
        which = np.union1d(np.flatnonzero(sw.crossed(g_a, g_star)), at_zero)
        which = np.union1d(which, [k]).astype(int)
        return t_star, g_star, which, k, iterates
