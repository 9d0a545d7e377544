"""An output held within limits by a discrete mode, written once for every block that
limits one: the PI and PID controllers' output z, a ``Limiter``'s y, a
``RateLimiter``'s rate.

The limited quantity follows a demand d (a controller's m_p + m_I (+ m_D), a
limiter's input u, a rate limiter's free rate (u - y)/T) between a lower bound lo
and an upper bound hi, in one of three modes kept in the component's ``modes`` (the
System's dict, ``LocalVector.modes``), under the key "mode":

    mode "free"         the output equation is  z = d
    mode <high>         z = hi      (saturated at the top; "high", a rate limiter's "up")
    mode <low>          z = lo      (saturated at the bottom; "low", or "down")

Never a clip inside Newton: in each mode the residual is smooth, and the switch
functions (seed eq. 10.13e), positive while the mode holds and crossing zero from
above when it must change (direction -1), let the integrator locate the change:

    upper   mode free: hi - d   (enter <high>)    mode <high>: d - hi   (back to free)
    lower   mode free: d - lo   (enter <low>)     mode <low>:  lo - d   (back to free)

Each crossing toggles its mode (``toggle``). At the start the mode is the one the
demand lies in (``mode_at``; a controller allows round-off, ``MODE_ROUNDOFF`` of the
range). A PI controller with anti-windup leaves saturation on the sign of its error
instead, and resets its integral (bumpless): it uses ``upper``/``lower`` for the
other cases and its own functions for those (``dnasim.library.controller``).
"""

from __future__ import annotations

from dnasim.model.component import Switch

__all__ = ["LimitedOutput", "MODE_ROUNDOFF", "output_range_problems", "LIMITED", "RATE_LIMITED"]

#: a start value of the demand within this fraction of the output range of a limit
#: counts as inside the limits (``LimitedOutput.mode_at`` with ``tol``)
MODE_ROUNDOFF = 1e-12


class LimitedOutput:
    """The modes, the output residual and the switch functions of a limited output
    (module doc). ``high``, ``low``: the names of the saturated modes ("high" and
    "low"; a rate limiter's "up" and "down"). Holds no state: the mode is in the
    component's ``modes``, so one instance serves every component."""

    KEY = "mode"
    FREE = "free"

    def __init__(self, high: str = "high", low: str = "low"):
        self.high = high
        self.low = low

    # ------------------------------------------------------------------ modes
    def mode(self, modes: dict) -> str:
        """The current mode ("free" before any is set)."""
        return modes.get(self.KEY, self.FREE)

    def reset(self, modes: dict) -> None:
        """The mode of a new run: free (``Component.reset_discrete_state``)."""
        modes[self.KEY] = self.FREE

    def mode_at(self, demand: float, lo: float, hi: float, tol: float = 0.0) -> str:
        """The mode the demand lies in: <high> above hi + tol, <low> below lo - tol,
        else free (``Component.init_discrete_state``)."""
        if demand > hi + tol:
            return self.high
        if demand < lo - tol:
            return self.low
        return self.FREE

    def start(self, modes: dict, demand: float, lo: float, hi: float, tol: float = 0.0) -> bool:
        """Set the mode of the start from the demand (``mode_at``); True when it changed."""
        old = self.mode(modes)
        modes[self.KEY] = mode = self.mode_at(demand, lo, hi, tol)
        return mode != old

    # --------------------------------------------------------------- residual
    def target(self, mode: str, demand: float, lo: float, hi: float) -> float:
        """What the output equals in ``mode``: the demand (free), hi or lo; the output
        equation's residual is z - target."""
        if mode == self.FREE:
            return demand
        return hi if mode == self.high else lo

    # --------------------------------------------------------------- switches
    def upper(self, demand: float, hi: float, mode: str) -> float:
        """The upper switch function: hi - d while not at <high>, d - hi at <high>."""
        d = hi - demand
        return -d if mode == self.high else d

    def lower(self, demand: float, lo: float, mode: str) -> float:
        """The lower switch function: d - lo while not at <low>, lo - d at <low>."""
        d = demand - lo
        return -d if mode == self.low else d

    def toggle(self, modes: dict, which: str) -> str:
        """Cross into ``which`` (from free) or back to free (from ``which``); returns
        the mode left."""
        old = self.mode(modes)
        modes[self.KEY] = self.FREE if old == which else which
        return old

    def switches(self, demand, lo, hi, names=("upper", "lower"), docs=None) -> list[Switch]:
        """The two ``Switch``es of a block whose demand, lower and upper bound at
        (t, x, xp) are ``demand(t, x, xp)``, ``lo(t, x)`` and ``hi(t, x)``: upper and
        lower of the module doc, each toggling its mode."""
        docs = docs or (f"enter/leave {self.high}", f"enter/leave {self.low}")

        def g_upper(t, x, xp):
            return self.upper(demand(t, x, xp), hi(t, x), self.mode(x.modes))

        def g_lower(t, x, xp):
            return self.lower(demand(t, x, xp), lo(t, x), self.mode(x.modes))

        def to_high(t, x, xp):
            self.toggle(x.modes, self.high)

        def to_low(t, x, xp):
            self.toggle(x.modes, self.low)

        return [
            Switch(names[0], g_upper, -1, to_high, docs[0]),
            Switch(names[1], g_lower, -1, to_low, docs[1]),
        ]


#: the output limits of the controllers and the ``Limiter`` (modes "high", "low")
LIMITED = LimitedOutput()
#: the rate limits of the ``RateLimiter`` (modes "up", "down")
RATE_LIMITED = LimitedOutput("up", "down")


def output_range_problems(comp, x) -> list[str]:
    """A controller's output z outside [z_min, z_max] at a state at rest (the steady
    start engages a limit instead; ``Component.steady_problems``)."""
    P = comp.params
    z, lo, hi = x["z"], P["z_min"], P["z_max"]
    tol = MODE_ROUNDOFF * max(abs(hi - lo), abs(hi), abs(lo))
    if lo - tol <= z <= hi + tol:
        return []
    return [
        f"controller '{comp.name}' ({type(comp).__name__}) has the output z = {z:.4g}, "
        f"outside its range [{lo:g}, {hi:g}]"
    ]
