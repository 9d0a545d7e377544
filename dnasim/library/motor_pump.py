"""MotorPump: a centrifugal pump (``Pump``) driven by an induction motor, with rotor inertia."""

from __future__ import annotations

import math

from dnasim.core.errors import PlantError
from dnasim.library.pump import Pump
from dnasim.model.component import Equation, Output, Param, SignalPort, Variable

#: omega_reg / omega_rated of the hydraulic torque tau_h = P omega/(omega^2 + omega_reg^2):
#: P/omega to 1e-6 relative at omega > omega_rated/1000, 0 at standstill
OMEGA_REG_REL = 1e-3


def kloss_torque(s: float, tau_k: float, s_k: float) -> float:
    """Kloss's induction-motor torque [N m] at slip s [-]: 2 tau_k s s_k/(s^2 + s_k^2)
    (tau_k the breakdown torque [N m] at the breakdown slip s_k [-]); odd in s, so a
    motor above synchronous speed (s < 0) brakes as a generator."""
    return 2.0 * tau_k * s * s_k / (s * s + s_k * s_k)


def breakdown_slip(s_rated: float, k: float) -> float:
    """s_k [-] of Kloss's formula through the rated point: tau_r/tau_k = 2 s_r s_k /
    (s_r^2 + s_k^2) with k = tau_k/tau_r > 1 gives s_k = s_r (k + sqrt(k^2 - 1)) (the
    root on the stable side, s_r < s_k)."""
    return s_rated * (k + math.sqrt(k * k - 1.0))


_MOTOR_PARAMS = (
    Param(
        "J", "kg.m2", None, "moment of inertia of the rotor, coupling and pump impeller", min=0.0
    ),
    Param("n_sync", "rad/s", None, 'synchronous speed of the motor (e.g. "1500 rpm")', min=0.0),
    Param("n_rated", "rad/s", None, "rated speed of the motor (below n_sync)", min=0.0),
    Param("P_rated", "W", None, "rated mechanical power of the motor at n_rated", min=0.0),
    Param(
        "breakdown",
        "1",
        2.5,
        "breakdown torque / rated torque of the motor (Kloss's tau_k/tau_r, > 1)",
        min=1.0,
    ),
    Param(
        "n_pump",
        "rad/s",
        None,
        "speed at which the head curve is given, n_0 (default: n_rated)",
        min=0.0,
    ),
    Param(
        "P_friction",
        "W",
        0.0,
        "bearing, seal and windage loss at n_rated (a torque linear in the speed)",
        min=0.0,
    ),
    Param(
        "supply",
        "1",
        1.0,
        "fraction of the motor torque (1: on, 0: tripped); a time function for a trip",
        min=0.0,
        max=1.0,
        time_function=True,
    ),
    Param(
        "speed0",
        "rad/s",
        None,
        "speed at the start from given states (default: n_rated)",
        min=0.0,
    ),
)


class MotorPump(Pump):
    """Centrifugal pump driven by an induction motor; the shaft speed omega [rad/s] is a
    state (rotor inertia), so a trip gives the run-down and a start the run-up.

    The hydraulics are the ``Pump``'s, all of them (head curve or table, efficiency,
    affinity laws, zero and reverse flow, NPSH and the cavitation check, the optional
    heated casing with its shut-off power), at the relative speed r = omega/n_0 (n_0 =
    ``n_pump``, default n_rated) instead of the parameter ``speed``. Symbols: J [kg m2]
    inertia, omega_s = n_sync, omega_r = n_rated [rad/s], tau_r = P_rated/omega_r [N m]
    rated torque, k = ``breakdown``, u(t) = ``supply`` [-], P [W] the pump's shaft
    power into the fluid (``Pump``), P_f = ``P_friction`` [W].

      speed      J domega/dt = tau_m - tau_h - tau_f                            [N m]
      motor      tau_m = u(t) 2 tau_k s s_k/(s^2 + s_k^2),  s = (omega_s - omega)/omega_s
                 (Kloss's formula; tau_k = k tau_r, s_k = s_r (k + sqrt(k^2 - 1)) through
                 the rated point s_r = (omega_s - omega_r)/omega_s, tau_m(s_r) = tau_r)
      hydraulic  tau_h = P omega/(omega^2 + omega_reg^2)   (= P/omega; omega_reg =
                 1e-3 omega_r keeps it finite at standstill, where P = 0)      [N m]
      friction   tau_f = (P_f/omega_r) omega/omega_r                           [N m]
      work       dW_motor/dt = tau_m omega,  dW_friction/dt = tau_f omega       [W]

    so that W_motor = W + W_friction + J (omega^2 - omega_0^2)/2 over any run (W the
    pump's work on the fluid): the rotor's energy balance. Kloss's curve is the
    steady-state torque of the motor (no electrical transients); its torque at
    standstill is 2 tau_k s_k/(1 + s_k^2), lower than a real cage motor's starting
    torque, so a run-up from rest is slower than on a test bed. A trip is u(t)
    stepping to 0 (a time function: ``{type = "step", ...}``); u < 1 may also stand
    for a reduced voltage (torque ~ V^2: u = (V/V_r)^2). With the pump's P_shutoff
    and M_casing the pump also absorbs P_0 r^3 at zero flow (disk friction,
    recirculation) and so brakes against a shut check valve; without them a pump at
    zero flow takes no power and only P_friction slows it. Reverse flow does not
    drive the rotor backwards (the ``Pump`` exchanges no work with reverse flow):
    a four-quadrant turbine mode is not modelled. The steady start solves
    tau_m = tau_h + tau_f on the stable side of the motor's curve (the guess is
    n_rated); a given start begins at ``speed0``.
    """

    PARAMS = tuple(p for p in Pump.PARAMS if p.name != "speed") + _MOTOR_PARAMS
    SIGNAL_INPUTS = ()
    SIGNAL_OUTPUTS = (
        *Pump.SIGNAL_OUTPUTS,
        SignalPort("omega", "rad/s", "shaft speed", variable="omega"),
    )

    def setup(self):
        P = self.params
        P["speed"] = None  # the speed is the state omega (Pump.speed is overridden)
        super().setup()
        name = f"component '{self.name}' (MotorPump)"
        missing = [k for k in ("J", "n_sync", "n_rated", "P_rated") if P[k] is None]
        if missing:
            raise PlantError(
                f"{name}: give {', '.join(missing)} (the rotor's inertia J [kg m2], the "
                'motor\'s synchronous and rated speeds [rad/s, or "1500 rpm"] and its '
                "rated power [W])"
            )
        ws, wr = P["n_sync"], P["n_rated"]
        if not wr < ws:
            raise PlantError(
                f"{name}: n_rated = {wr:g} rad/s must be below n_sync = {ws:g} rad/s (an "
                "induction motor runs with slip)"
            )
        k = P["breakdown"]
        if not k > 1.0:
            raise PlantError(f"{name}: breakdown = {k:g} must be > 1 (tau_k > tau_rated)")
        self.tau_rated = P["P_rated"] / wr
        self.tau_k = k * self.tau_rated
        self.s_rated = (ws - wr) / ws
        self.s_k = breakdown_slip(self.s_rated, k)
        self.n_0 = P["n_pump"] if P["n_pump"] is not None else wr
        self.omega_reg = OMEGA_REG_REL * wr

    # ----------------------------------------------------------- declarations
    def signal_inputs(self):
        return []

    def speed_reads(self):
        return ("omega",)

    def speed(self, t, x):
        """Relative speed r = omega/n_0 [-] of the head curve's affinity laws."""
        return x["omega"] / self.n_0

    def variables(self):
        P = self.params
        wr = P["n_rated"]
        E = max(P["P_rated"], 1.0)
        return super().variables() + [
            Variable("omega", "rad/s", wr, doc="shaft speed"),
            Variable("tau_m", "N.m", self.tau_rated, doc="motor torque"),
            Variable("tau_h", "N.m", self.tau_rated, doc="hydraulic torque of the pump, P/omega"),
            Variable(
                "W_motor",
                "J",
                E,
                doc="work of the motor on the shaft, integral of tau_m omega dt",
                accumulator=True,
            ),
            Variable(
                "W_friction",
                "J",
                E,
                doc="bearing and windage work, integral of tau_f omega dt",
                accumulator=True,
            ),
        ]

    def equations(self):
        J = self.params["J"]
        return super().equations() + [
            Equation(
                "speed",
                y=("tau_m", "tau_h", "omega"),
                yp=("omega",),
                unit="N.m",
                doc=f"{J:g} domega/dt = tau_m - tau_h - tau_f(omega)",
                residual=lambda t, x, xp: (
                    J * xp["omega"] - x["tau_m"] + x["tau_h"] + self.friction_torque(x["omega"])
                ),
            ),
            Equation(
                "motor",
                y=("tau_m", "omega"),
                unit="N.m",
                doc="tau_m = u(t) 2 tau_k s s_k/(s^2 + s_k^2)",
                residual=lambda t, x, xp: x["tau_m"] - self.motor_torque(t, x["omega"]),
            ),
            Equation(
                "hydraulic",
                y=("tau_h", "P", "omega"),
                unit="N.m",
                doc="tau_h = P omega/(omega^2 + omega_reg^2)",
                residual=lambda t, x, xp: x["tau_h"] - self.hydraulic_torque(x["P"], x["omega"]),
            ),
            Equation(
                "motor_work",
                y=("tau_m", "omega"),
                yp=("W_motor",),
                unit="W",
                doc="dW_motor/dt = tau_m omega",
                residual=lambda t, x, xp: xp["W_motor"] - x["tau_m"] * x["omega"],
            ),
            Equation(
                "friction_work",
                y=("omega",),
                yp=("W_friction",),
                unit="W",
                doc="dW_friction/dt = tau_f omega",
                residual=lambda t, x, xp: (
                    xp["W_friction"] - self.friction_torque(x["omega"]) * x["omega"]
                ),
            ),
        ]

    # --------------------------------------------------------------- physics
    def motor_torque(self, t, omega) -> float:
        """tau_m [N m] at speed omega [rad/s] and time t (supply u(t))."""
        ws = self.params["n_sync"]
        s = (ws - omega) / ws
        return self.param_at("supply", t) * kloss_torque(s, self.tau_k, self.s_k)

    def hydraulic_torque(self, P, omega) -> float:
        """tau_h = P omega/(omega^2 + omega_reg^2) [N m] from the shaft power P [W]."""
        return P * omega / (omega * omega + self.omega_reg**2)

    def friction_torque(self, omega) -> float:
        """tau_f = (P_f/omega_r) omega/omega_r [N m]."""
        wr = self.params["n_rated"]
        return self.params["P_friction"] * omega / (wr * wr)

    def outputs(self):
        return super().outputs() + [
            Output("r", "1", "relative speed omega/n_0 of the head curve"),
            Output("P_motor", "W", "mechanical power of the motor, tau_m omega"),
        ]

    def output_values(self, t, x, xp):
        return super().output_values(t, x, xp) + [
            x["omega"] / self.n_0,
            x["tau_m"] * x["omega"],
        ]

    # ---------------------------------------------------------- initialisation
    def initial_guess(self, t0, x):
        P = self.params
        w = P["speed0"] if P["speed0"] is not None else P["n_rated"]
        x["omega"] = w
        super().initial_guess(t0, x)
        # the pump's guess at relative speed 1 (Pump.initial_guess), rescaled by r^3
        x["tau_m"] = self.motor_torque(t0, w)
        x["tau_h"] = self.hydraulic_torque(x["P"], w)
        x["W_motor"] = 0.0
        x["W_friction"] = 0.0
