"""PIController: proportional-integral controller with output limits (seed eqs. 10.13a-e).

``dnasim.library.pid.PIDController`` is the general controller (D part,
back-calculation anti-windup, tracking, per-unit gains); this one is the seed's."""

from __future__ import annotations

from dnasim.library.submodels.limited_output import (
    LIMITED,
    MODE_ROUNDOFF,
    output_range_problems,
)
from dnasim.model.component import (
    Component,
    Equation,
    Output,
    Param,
    SignalPort,
    Switch,
    Variable,
)

__all__ = ["PIController", "check_set_point_unit", "output_range_problems", "MODE_ROUNDOFF"]


def check_set_point_unit(comp) -> None:
    """Raise PlantError when a controller's set point signal (input ``set_point``)
    and its measured signal differ in dimension (a cascade whose master gives its
    output in another unit than the slave measures)."""
    have = getattr(comp, "input_units", {}).get("set_point")
    want = comp.measured_unit
    if not comp.setpoint_from_signal or have in (None, "*") or want == "*":
        return
    from dnasim.core.errors import PlantError
    from dnasim.core.units import UnitError, parse_unit

    try:
        same = parse_unit(have).dims == parse_unit(want).dims
    except UnitError:
        return
    if not same:
        raise PlantError(
            f"component '{comp.name}' ({type(comp).__name__}): the set point signal [{have}] "
            f"and the measured signal [{want}] differ in dimension; a cascade's master "
            f"controller must give its output in the slave's measured unit ({want})"
        )


class PIController(Component):
    """PI controller with an output limited to [z_min, z_max] by switch variables.

    Symbols: e error, m_p proportional part, m_I integral part, v = m_p + m_I the
    demanded output, z the output (signal ``z``).

      error         e = s (measured - w),  s = +1 ("measured-setpoint") or -1             (10.13a)
      proportional  m_p = Kp e                                                            (10.13c)
      integral      dm_I/dt = KI e          (= 0 while saturated, if anti_windup)          (10.13d)
      output        z = v                   mode "free"                                   (10.13b)
                    z = z_max               mode "high" (saturated at the top)
                    z = z_min               mode "low"

    Switch functions (10.13e), positive while the mode holds, crossing zero from
    above when it must change (direction -1; the limited output of
    ``dnasim.library.submodels.limited_output``, shared with the PID and the limiters):
      upper: mode free: z_max - v  -> enter "high";  mode high: v - z_max -> leave to "free"
      lower: mode free: v - z_min  -> enter "low";   mode low:  z_min - v -> leave to "free"
    With anti_windup the integrator is held while saturated, so v - z_max would
    chatter (v falls at once with m_p, the free mode then pushes it back): instead
    the saturated mode is left when the error changes sign (upper: g = sgn(Kp) e,
    lower: g = -sgn(Kp) e), and m_I is reset to z_max - m_p (z_min - m_p) so the
    output stays continuous (bumpless transfer).
    Given start: m_I starts at ``integral0``.

    The set point w [measured unit] is the parameter ``setpoint`` (a number or a
    time function) or, when that is not given, the signal input ``set_point``
    (cascade control: a master controller's output in this controller's
    measured unit).
    """

    PARAMS = (
        Param("Kp", "1", doc="proportional gain [output unit per measured unit]", per_signal=-1),
        Param(
            "KI",
            "1/s",
            0.0,
            "integral gain [output unit per measured unit and second]",
            per_signal=-1,
        ),
        Param(
            "setpoint",
            "1",
            None,
            "set point, in the unit of the measured signal (not given: the signal input set_point)",
            time_function=True,
            per_signal=1,
        ),
        Param("z_min", "1", 0.0, "lower output limit"),
        Param("z_max", "1", 1.0, "upper output limit"),
        Param(
            "error_sign",
            "1",
            "measured-setpoint",
            "e = measured - setpoint, or the reverse",
            kind="string",
            choices=("measured-setpoint", "setpoint-measured"),
        ),
        Param(
            "anti_windup",
            "1",
            True,
            "hold the integrator while saturated (false: the seed's plain eqs. 10.13)",
            kind="bool",
        ),
        Param("integral0", "1", 0.0, "initial integral part m_I (given start)"),
        Param(
            "measured_nominal",
            "1",
            100.0,
            "typical magnitude of the measured signal (scales)",
            min=0.0,
            per_signal=1,
        ),
    )
    SIGNAL_INPUTS = (
        SignalPort("measured", "*", "measured value (any unit)"),
        SignalPort(
            "set_point",
            "*",
            "set point w in the measured unit (when the parameter 'setpoint' is not given)",
        ),
    )
    SIGNAL_OUTPUTS = (SignalPort("z", "1", "limited output", variable="z"),)
    USES_MEDIUM = False

    def setup(self):
        if not self.params["z_max"] > self.params["z_min"]:
            from dnasim.core.errors import PlantError

            raise PlantError(f"component '{self.name}': z_max must be greater than z_min")
        self.sign = 1.0 if self.params["error_sign"] == "measured-setpoint" else -1.0
        #: the set point is the signal input set_point (cascade), not a time function
        self.setpoint_from_signal = (
            self.params["setpoint"] is None and "setpoint" not in self.signal_unit_values
        )

    def signal_inputs(self):
        return list(self.SIGNAL_INPUTS) if self.setpoint_from_signal else [self.SIGNAL_INPUTS[0]]

    def set_point_value(self, t, x) -> float:
        """The set point w [measured unit]: the signal input or the time function."""
        if self.setpoint_from_signal:
            return x["set_point"]
        return self.param_at("setpoint", t)

    def reset_discrete_state(self, modes):
        LIMITED.reset(modes)

    @staticmethod
    def _mode(x):
        """The mode, from the System-owned dict (``LocalVector.modes``)."""
        return LIMITED.mode(x.modes)

    @property
    def measured_unit(self) -> str:
        """Unit of the linked measured signal ("1" before the plant is assembled)."""
        return getattr(self, "input_units", {}).get("measured", "1") or "1"

    @property
    def error_unit(self) -> str:
        """Unit of the control error: a difference of the measured unit (a temperature
        difference is "delta_K", so that it is never shifted by 273.15 for display)."""
        u = self.measured_unit
        return "delta_K" if u == "K" else u

    def outputs(self):
        """The set point and the output limits, recorded in the results for plots."""
        return [
            Output("setpoint", self.measured_unit, "set point, in the unit of the measured signal"),
            Output("z_min", "1", "lower output limit"),
            Output("z_max", "1", "upper output limit"),
        ]

    def output_values(self, t, x, xp):
        P = self.params
        return [self.set_point_value(t, x), P["z_min"], P["z_max"]]

    def variables(self):
        check_set_point_unit(self)
        return [
            Variable("e", self.error_unit, self.params["measured_nominal"] * 0.01, doc="error"),
            Variable("m_p", "1", 1.0, doc="proportional part"),
            Variable("m_I", "1", 1.0, doc="integral part"),
            Variable("z", "1", 1.0, doc="output"),
        ]

    def equations(self):
        """The equations of the class doc (their residuals: ``row_values``)."""
        return [
            Equation(
                "error",
                y=("e", "measured", *(("set_point",) if self.setpoint_from_signal else ())),
                doc="e = sign (measured - w)   (10.13a)",
            ),
            Equation("proportional", y=("m_p", "e"), doc="m_p = Kp e"),
            Equation(
                "integral",
                y=("e",),
                yp=("m_I",),
                doc="dm_I/dt = KI e (0 while saturated with anti-windup)   (10.13c)",
            ),
            Equation(
                "output",
                y=("z", "m_p", "m_I"),
                doc="z = m_p + m_I (free), z_max (high), z_min (low)   (10.13b)",
            ),
        ]

    def row_reads(self):
        """The names ``row_values`` reads (``Component.row_reads``)."""
        w = ("set_point",) if self.setpoint_from_signal else ()
        return ("e", "measured", "m_p", "m_I", "z") + w, ("m_I",)

    def row_values(self, t, v, vp, modes):
        """The equations of the class doc, their residuals [output unit, its rate for
        the integral], in the discrete mode ``modes["mode"]``:

          error         e - s (measured - w)
          proportional  m_p - Kp e
          integral      dm_I/dt - KI e      (dm_I/dt while saturated, if anti_windup)
          output        z - (m_p + m_I)     (free),  z - z_max (high),  z - z_min (low)
        """
        P = self.params
        e, measured, m_p, m_I, z, *w = v
        w = w[0] if self.setpoint_from_signal else self.param_at("setpoint", t)
        mode = LIMITED.mode(modes)
        hold = P["anti_windup"] and mode != LIMITED.FREE
        output = z - LIMITED.target(mode, m_p + m_I, P["z_min"], P["z_max"])
        return [
            e - self.sign * (measured - w),
            m_p - P["Kp"] * e,
            vp[0] - (0.0 if hold else P["KI"] * e),
            output,
        ]

    # ----------------------------------------------------------------- switches
    def _gain_sign(self):
        return 1.0 if (self.params["Kp"] + self.params["KI"]) >= 0 else -1.0

    def _upper(self, t, x, xp):
        mode = self._mode(x)
        if mode == "high" and self.params["anti_windup"]:
            # leave when the error turns to drive the output down
            return self._gain_sign() * x["e"]
        return LIMITED.upper(x["m_p"] + x["m_I"], self.params["z_max"], mode)

    def _lower(self, t, x, xp):
        mode = self._mode(x)
        if mode == "low" and self.params["anti_windup"]:
            return -self._gain_sign() * x["e"]
        return LIMITED.lower(x["m_p"] + x["m_I"], self.params["z_min"], mode)

    def _toggle_upper(self, t, x, xp):
        if LIMITED.toggle(x.modes, "high") == "high" and self.params["anti_windup"]:
            x["m_I"] = self.params["z_max"] - x["m_p"]  # bumpless: v = z_max

    def _toggle_lower(self, t, x, xp):
        if LIMITED.toggle(x.modes, "low") == "low" and self.params["anti_windup"]:
            x["m_I"] = self.params["z_min"] - x["m_p"]

    def switches(self):
        return [
            Switch("upper", self._upper, -1, self._toggle_upper, "enter/leave saturation at z_max"),
            Switch("lower", self._lower, -1, self._toggle_lower, "enter/leave saturation at z_min"),
        ]

    def init_discrete_state(self, t0, x, xp):
        """The mode of the start: saturated only when v is beyond a limit by more than
        round-off (MODE_ROUNDOFF of the output range). plants/drum_boiler.toml starts
        with e = 0, v = 0 = z_min: its start's Newton left v = -1.1e-44, which chose
        "low" with e of the sign that leaves it at once, the leave switch never
        crossed, and the feed stayed off (the level fell to 24 m3 instead of being held
        at 67 m3)."""
        P = self.params
        tol = MODE_ROUNDOFF * max(abs(P["z_max"] - P["z_min"]), abs(P["z_max"]), abs(P["z_min"]))
        return LIMITED.start(x.modes, x["m_p"] + x["m_I"], P["z_min"], P["z_max"], tol)

    def initial_guess(self, t0, x):
        x["m_I"] = self.params["integral0"]
        x["e"] = 0.0
        x["m_p"] = 0.0
        x["z"] = min(max(self.params["integral0"], self.params["z_min"]), self.params["z_max"])

    def free_at_rest(self, t0, x):
        """Saturated (mode "high" or "low"), the output is the limit and no equation
        reads the integral m_I: the steady start keeps it (``Component.free_at_rest``).
        With anti_windup it is held (dm_I/dt = 0, the state is at rest); without, it
        winds at dm_I/dt = KI e."""
        return ("m_I",) if self._mode(x) != LIMITED.FREE else ()

    def design_values(self, t0, x):
        return {"opening": x["z"]}

    def steady_problems(self, t0, x):
        return output_range_problems(self, x)
