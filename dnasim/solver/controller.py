"""The step-size and order controller of the BDF stepper.

``StepController`` is fed the error estimates of each step by the stepper
(``bdf.NordsieckBDF``) and answers with the next order and the step ratio
eta = h_new / h; it never touches the Nordsieck array, which the stepper
rescales (as scipy's ``OdeSolver`` and diffrax keep the controller apart from
the step). It keeps the controller's own state: the steps taken at the current
order, whether the next decision follows a (re)start, and the stability-limit
detector's run of held steps and the step sizes at which orders were found
stability-limited.

    eta_k = (err_k / ERROR_TARGET)^(-1/(k+1))    (``eta``)

for the orders k = q - 1, q, q + 1 (the lower and higher only after q + 1 steps at
this order, ``wants_order_estimates``), through the smooth limiter
eta <- 1 + atan(eta - 1) (Soderlind's, kappa = 1).
"""

from __future__ import annotations

import math
from collections.abc import Callable

ERROR_TARGET = 0.03  # the step-size formula aims at 0.03 of the tolerance (IDA: 0.5), see README
ETA_MAX_FIRST = 1.0e4 / 10.0  # growth allowed right after the (tiny) initial step
CROSSING_OVERSHOOT = 1.1  # a failed step crossing a switch ends 10 % past the crossing
ORDER_UP_BIAS = 1.2  # a higher order must promise 20 % more step to be chosen
# Stability-limit detection (see StepController.stability_limited): at order q >=
# MIN_Q_STAB, error estimates that do not fall with the order (each at least FLAT_RATIO
# of the next lower order's) at a step limited by its error and held within 20 % of one
# size for FLAT_STEPS_PER_ORDER (q + 1) steps mean the step is held by the method's
# stability region, not by the solution: the order drops by one.
FLAT_RATIO = 0.5
FLAT_STEPS_PER_ORDER = 2
MIN_Q_STAB = 4  # orders below are left alone: see stability_limited


def eta(error: float, order: int) -> float:
    """Step ratio that brings the local error of ``order`` to ERROR_TARGET."""
    return (error / ERROR_TARGET + 1e-10) ** (-1.0 / (order + 1))


class StepController:
    """Chooses the next step size (as a ratio eta) and order from error estimates.

    Parameters
    ----------
    max_order : highest order, 1..5
    fixed_order, fixed_step : for order-verification tests only: keep q (and h)

    State: ``steps_at_this_order``, ``first_step`` (the next decision follows a
    start or restart: fast growth at order 1), ``flat_steps``/``flat_h`` (the
    stability-limit detector's run) and ``stability_h`` (order -> the step size [s]
    at which it was found stability-limited; kept across restarts).
    """

    def __init__(self, max_order: int, fixed_order: bool = False, fixed_step: bool = False):
        self.max_order = max_order
        self.fixed_order = fixed_order
        self.fixed_step = fixed_step
        self.steps_at_this_order = 0
        self.first_step = True
        self.flat_steps, self.flat_h = 0, 0.0
        # order -> the step size [s] at which that order was found stability-limited;
        # kept across restarts (the plant's fast modes stay), see stability_limited
        self.stability_h: dict[int, float] = {}

    def restart(self, h: float) -> None:
        """A (re)start at order 1 with step h: fast growth allowed after the first step."""
        self.steps_at_this_order = 0
        self.first_step = True
        self.flat_steps, self.flat_h = 0, h

    def accepted(self) -> None:
        """One more step accepted at the current order."""
        self.steps_at_this_order += 1

    def order_changed(self) -> None:
        self.steps_at_this_order = 0
        self.flat_steps = 0

    def wants_order_estimates(self, q: int) -> bool:
        """Whether ``choose`` compares orders q - 1 and q + 1 (after q + 1 steps at q)."""
        return self.steps_at_this_order >= q + 1 and not self.fixed_order

    # -- after an accepted step ----------------------------------------------------------
    def choose(
        self,
        q: int,
        h: float,
        error: float,
        err_down: float | None,
        err_up: float | None,
        failed_this_step: bool,
    ) -> tuple[int, float]:
        """After an accepted step of order q and size h: (new order, eta).

        ``error`` is order q's estimate (in units of the tolerance), ``err_down`` and
        ``err_up`` those of orders q - 1 and q + 1 (None where not available; read
        only when ``wants_order_estimates(q)``). eta_k = (err_k / ERROR_TARGET)^(-1/(k+1));
        the chosen eta goes through the smooth limiter eta <- 1 + atan(eta - 1): no
        dead band, so after a transient h keeps growing until the error estimate
        limits it, and a change of the estimate at round-off level changes h at
        round-off level, never the step count by a jump. Growth is at most 1 + pi/2
        per step and never right after a failure. A step held by the stability region
        of BDF4 or 5, not by the solution, lowers the order (``stability_limited``).
        eta = 1.0 exactly: keep h.
        """
        if self.fixed_step:
            return q, 1.0
        if self.first_step:
            # The initial step is deliberately tiny: let it grow fast, at order 1.
            self.first_step = False
            e = min(eta(error, 1), ETA_MAX_FIRST)
            return q, (e if e >= 2.0 and not failed_this_step else 1.0)
        new_q, e = q, eta(error, q)
        if self.wants_order_estimates(q):
            if err_down is not None:
                eta_down = eta(err_down, q - 1)
                if eta_down > e:
                    new_q, e = q - 1, eta_down
            if self.stability_limited(q, h, error, err_down, err_up):
                new_q, e = q - 1, min(eta_down, 1.0)
            elif q < self.max_order and err_up is not None:
                eta_up = eta(err_up, q + 1) / ORDER_UP_BIAS
                if eta_up > e and h * eta_up < 0.5 * self.stability_h.get(q + 1, math.inf):
                    new_q, e = q + 1, eta_up
        e = 1.0 + math.atan(e - 1.0)
        if failed_this_step:
            e = min(e, 1.0)
        return new_q, e

    def stability_limited(self, q, h, error, err_down, err_up) -> bool:
        """Whether order q's step h is held by its stability region, not by the solution.

        BDF3, 4 and 5 are not A-stable (A(86 deg), A(73 deg), A(51 deg)). Where a stiff,
        strongly non-normal mode lies near that boundary (the upwind transport of a pipe
        of many volumes: its eigenvalues all sit at -1/tau, its pseudospectrum fills the
        disc of radius 1/tau about them, touching the imaginary axis), a step beyond the
        limit lets a parasitic component grow until the error test holds it back. The
        step then stays near the limit with the local error at its target, and the
        error estimates of orders q - 1, q and q + 1 are of one size (the parasitic
        component is in every difference), where a resolved solution gives estimates
        falling by a factor ~h/tau_solution per order. Measured on the 1000-volume steam
        pipe (tests/field/long_pipe_step.toml) after its temperature front has left:
        order 4 held h at 4 ms for 255 steps with e3, e4, e5 = 0.045, 0.030, 0.024 of the
        tolerance, where order 3 took 12 steps of 0.13 s over the same interval.

        The test, a simple form of CVODE's stability-limit detection (STALD; IDA has
        none): q >= MIN_Q_STAB, the error at least half its target, e_q >= FLAT_RATIO
        e_(q-1) and e_(q+1) >= FLAT_RATIO e_q, on FLAT_STEPS_PER_ORDER (q + 1) accepted
        steps in a row whose h stays within 20 % of the first's. Then the order drops
        by one and the step size is remembered: order q is raised to again only at
        steps below half of it (a smaller h is inside the stability region); the
        memory is kept across restarts, the plant's fast modes being the same.

        Why these conditions (measured): without the held-step condition the
        transistor amplifier of benchmarks/solver_vs_peers.py, a resolved oscillation
        whose estimates are also flat in the order while h follows the input, lost one
        digit at rtol 1e-8 (7.25 -> 6.16) for 33 % more steps; with it the Test Set
        counts are unchanged. At order 3 (A(86 deg)) the test fired on the pipe in its
        smooth phase, where order 2 then took 44 steps against order 4's 17 over 5 to
        61 s, and a larger error; so orders below 4 are left alone.
        """
        if q < MIN_Q_STAB or err_down is None or err_up is None:
            self.flat_steps = 0
            return False
        flat = (
            error >= 0.5 * ERROR_TARGET
            and error >= FLAT_RATIO * err_down
            and err_up >= FLAT_RATIO * error
        )
        if not flat:
            self.flat_steps = 0
            return False
        if self.flat_steps == 0 or not 0.8 < h / self.flat_h < 1.25:
            self.flat_steps, self.flat_h = 0, h  # a new run at this step size
        self.flat_steps += 1
        if self.flat_steps < FLAT_STEPS_PER_ORDER * (q + 1):
            return False
        self.flat_steps = 0
        self.stability_h[q] = h
        return True

    # -- after a rejected step -----------------------------------------------------------
    def after_error_failure(
        self, q: int, error: float, n_fail: int, lower_order_error: Callable[[], float]
    ) -> tuple[int, float]:
        """After the n_fail-th failed error test of this step at order q: (new order, eta).

        From the third failure on: order 1 and a quarter of the step. Before: the eta
        of order q's estimate, or of order q - 1's (``lower_order_error()``, asked only
        when q > 1) where it promises more, within [0.1, 0.9], at most 0.25 at the
        second failure.
        """
        self.steps_at_this_order = 0
        if n_fail >= 3:
            return (q if self.fixed_order else 1), 0.25
        e = eta(error, q)
        new_q = q
        if q > 1 and not self.fixed_order:
            eta_down = eta(lower_order_error(), q - 1)
            if eta_down > e:
                new_q, e = q - 1, eta_down
        e = min(max(e, 0.1), 0.9)
        if n_fail == 2:
            e = min(e, 0.25)
        return new_q, e

    def after_newton_failure(self, t: float, h: float, t_crossing: float | None) -> float:
        """Step ratio after a Newton failure of the step from t with size h: 0.25, or
        less to end just past a switch predicted to cross at ``t_crossing``.

        A phase line is a kink of the residual: the Newton of a step whose predictor
        carries a volume across it starts on one piece and must converge on the
        other, and the step size was cut by 4 again and again while the crossing
        stayed inside the step. When the predictor polynomial (the last accepted
        step's interpolant, extrapolated) crosses a restart switch in the step, the
        step is shortened to end a little (CROSSING_OVERSHOOT) past the earliest
        predicted crossing: only that crossing is left in the step, the predictor at
        its end lies on the new side with the solution, and the finite-difference
        matrix is built there. The driver then locates the crossing on the accepted
        step and restarts at order 1 (seed sec. 10.2.1).
        """
        self.steps_at_this_order = 0
        e = 0.25
        if t_crossing is not None:
            eta_c = CROSSING_OVERSHOOT * (t_crossing - t) / h
            if 0.0 < eta_c < 0.9:
                e = min(max(eta_c, 1e-3), 0.9)
        return e
