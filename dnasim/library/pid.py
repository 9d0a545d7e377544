"""PIDController: PID with a filtered D part, output limits as switch variables,
back-calculation anti-windup, tracking/activation (bumpless transfer) and per-unit gains."""

from __future__ import annotations

import math

from dnasim.core.errors import PlantError
from dnasim.library.controller import check_set_point_unit
from dnasim.library.submodels.limited_output import LIMITED, output_range_problems
from dnasim.model.component import Component, Equation, Output, Param, SignalPort, Switch, Variable

__all__ = ["PIDController"]


class PIDController(Component):
    """PID controller with a filtered D part, output limits as switch variables,
    back-calculation anti-windup, tracking/activation and per-unit gains.

    Symbols (units: [m] the measured signal's unit, [u] the output's unit ``unit``):

      error         e = s (measured - w)                        [m]   s = +1 or -1 (error_sign)
      proportional  m_p = Kp e                                  [u]
      derivative    (T_d/N) dx_f/dt = e_D - x_f,   e_D = s (measured - c_d w(t))        [m]
                    m_D = Kp N (e_D - x_f)                      [u]   (T_d > 0; else m_D = 0)
      integral      dm_I/dt = Kp/T_i e + (z - v)/T_t            [u/s] (automatic, anti_windup)
                    dm_I/dt = Kp/T_i e                                (automatic, no anti-windup)
                    dm_I/dt = (z - v)/T_t                             (manual: tracking)
      demand        v = m_p + m_I + m_D                         [u]
      output        z = v (mode free), z_max (high), z_min (low), z_track (manual)   [u]

    The set point w [m] is the parameter ``setpoint`` (a number or a time
    function w(t)) or, when that is not given, the signal input ``set_point``
    (cascade control: a master controller's output, ``inputs = { set_point =
    "master.z" }``; the master's ``unit`` must be the slave's measured unit).

    Transfer function from e to v in the free mode (T_i, T_d > 0):
      Kp (1 + 1/(T_i s) + T_d s / (1 + T_d s / N)).

    The D part acts on e_D: with the set-point weight c_d = 0 (default) on the
    measurement only, so a set-point step gives no derivative kick. Its filter time
    constant is T_d/N.

    Output limits are switch variables (seed eq. 10.13e; the limited output of
    ``dnasim.library.submodels.limited_output``), positive while the mode holds,
    direction -1:
      upper: mode free: z_max - v -> "high";  mode high: v - z_max -> back to "free"
      lower: mode free: v - z_min -> "low";   mode low:  z_min - v -> back to "free"

    Back-calculation anti-windup (default on): while saturated, z - v != 0 drives
    the integral back with the tracking time constant T_t (default sqrt(T_i T_d),
    or T_i for a PI), so v stays near the limit: at rest in saturation
    v - z_max = T_t Kp e / T_i. v is continuous, so the mode is left when v crosses
    the limit, without a reset and without chattering. In the free mode z = v and the
    tracking term is zero.

    Tracking and activation (bumpless transfer): ``active`` is a time function (1:
    automatic, 0: manual). In manual the output is z_track (the signal input
    ``track`` when ``tracking = true``, else the time function ``z_manual``) and the
    integral tracks it, dm_I/dt = (z_track - v)/T_t, so at the switch to automatic v
    is within the tracking error of z: the output does not jump. With ``tracking =
    true`` the input ``track`` is also the actuator position used by the
    anti-windup in automatic: z_track replaces z in (z - v)/T_t.

    Per-unit gains: give ``Kc`` [1] and ``measured_span`` [m] instead of Kp; then
    Kp = Kc * output_span / measured_span, output_span = z_max - z_min unless given.

    Units: with ``unit`` the output's SI unit ("W" for a firing rate), Kp may be
    written in the output unit per measured unit (Kp = "4 MW/bar" of a pressure
    controller is 40 W/Pa) and z_min, z_max, output_span, z_manual and integral0 in
    the output unit ("200 MW"); numbers are SI. A value of another dimension is refused
    with the unit expected.
    """

    PARAMS = (
        Param(
            "Kp",
            "1",
            None,
            "proportional gain [output unit per measured unit]",
            per_signal=-1,
            per_output=1,
        ),
        Param("Kc", "1", None, "per-unit gain (instead of Kp; needs measured_span)"),
        Param("measured_span", "1", None, "span of the measured signal (per unit)", per_signal=1),
        Param(
            "output_span",
            "1",
            None,
            "span of the output (per unit; default z_max - z_min) [output unit]",
            per_output=1,
        ),
        Param("T_i", "s", None, "integral time (not given: no integral part)", min=0.0),
        Param("T_d", "s", 0.0, "derivative time (0: no D part)", min=0.0),
        Param("N", "1", 10.0, "derivative filter: time constant T_d/N", min=0.0),
        Param("c_d", "1", 0.0, "set-point weight in the D part (0: D on the measurement)"),
        Param(
            "setpoint",
            "1",
            None,
            "set point w(t), in the unit of the measured signal (not given: the signal "
            "input set_point)",
            time_function=True,
            per_signal=1,
        ),
        Param("z_min", "1", 0.0, "lower output limit [output unit]", per_output=1),
        Param("z_max", "1", 1.0, "upper output limit [output unit]", per_output=1),
        Param("unit", "1", "1", 'unit of the output z (SI, e.g. "1", "kg/s")', kind="string"),
        Param(
            "error_sign",
            "1",
            "measured-setpoint",
            "e = measured - setpoint, or the reverse",
            kind="string",
            choices=("measured-setpoint", "setpoint-measured"),
        ),
        Param("anti_windup", "1", True, "back-calculation anti-windup", kind="bool"),
        Param("T_t", "s", None, "tracking time (default sqrt(T_i T_d), or T_i)", min=0.0),
        Param(
            "tracking", "1", False, "use the signal input 'track' (actuator position)", kind="bool"
        ),
        Param(
            "active",
            "1",
            1.0,
            "1: automatic, 0: manual (output z_track); may vary in time",
            time_function=True,
            min=0.0,
            max=1.0,
        ),
        Param(
            "z_manual",
            "1",
            None,
            "manual output when tracking = false [output unit]",
            time_function=True,
            per_output=1,
        ),
        Param(
            "integral0",
            "1",
            0.0,
            "initial integral part m_I (given start) [output unit]",
            per_output=1,
        ),
        Param(
            "measured_nominal",
            "1",
            100.0,
            "typical magnitude of the measured signal (scales the tolerance of e)",
            min=0.0,
            per_signal=1,
        ),
    )
    SIGNAL_INPUTS = (
        SignalPort("measured", "*", "measured value (any unit)"),
        SignalPort("track", "*", "actuator position / manual value (only with tracking = true)"),
        SignalPort(
            "set_point",
            "*",
            "set point w in the measured unit (when the parameter 'setpoint' is not given)",
        ),
    )
    SIGNAL_OUTPUTS = (SignalPort("z", "1", "limited output", variable="z"),)
    USES_MEDIUM = False
    #: the parameter holding the output's unit: Kp, the limits and the manual value
    #: may be written in it ("4 MW/bar", "200 MW" with unit = "W"; ``Param.per_output``)
    OUTPUT_UNIT_PARAM = "unit"

    def setup(self):
        P = self.params
        name = self.name
        if not P["z_max"] > P["z_min"]:
            raise PlantError(f"component '{name}': z_max must be greater than z_min")
        span_out = P["output_span"] if P["output_span"] is not None else P["z_max"] - P["z_min"]
        # given with a unit of the measured signal ("4 MW/bar"): converted once the link
        # is known (``Component.resolve_signal_units``, which runs this setup again)
        deferred = self.signal_unit_values
        if (P["Kp"] is None and "Kp" not in deferred) == (P["Kc"] is None):
            raise PlantError(
                f"component '{name}': give the gain as Kp [output unit per measured unit] or as "
                "the per-unit gain Kc with measured_span, one of them"
            )
        if P["Kc"] is not None and "measured_span" in deferred:
            self.Kp = None  # until measured_span is in SI
        elif P["Kc"] is not None:
            if not P["measured_span"] or P["measured_span"] <= 0:
                raise PlantError(
                    f"component '{name}': the per-unit gain Kc needs measured_span > 0"
                )
            self.Kp = P["Kc"] * span_out / P["measured_span"]
        else:
            self.Kp = P["Kp"]
        T_i, T_d = P["T_i"], P["T_d"]
        if T_i is not None and not T_i > 0:
            raise PlantError(f"component '{name}': T_i must be > 0 s (leave it out for no I part)")
        if T_d > 0 and not P["N"] > 0:
            raise PlantError(f"component '{name}': the derivative filter needs N > 0")
        if P["T_t"] is not None:
            self.T_t = P["T_t"]
        elif T_i is not None:
            self.T_t = math.sqrt(T_i * T_d) if T_d > 0 else T_i
        else:
            self.T_t = T_d if T_d > 0 else 1.0
        if not self.T_t > 0:
            raise PlantError(f"component '{name}': the tracking time T_t must be > 0 s")
        manual = any(P["active"](t) < 0.5 for t in (0.0, *P["active"].breakpoints))
        #: whether the output ever follows z_track (then the output equation reads it)
        self.has_manual = manual
        if manual and not P["tracking"] and P["z_manual"] is None:
            raise PlantError(
                f"component '{name}': 'active' switches to manual, so the output needs a manual "
                "value: give z_manual, or tracking = true with inputs.track"
            )
        self.sign = 1.0 if P["error_sign"] == "measured-setpoint" else -1.0
        self.span_out = span_out
        #: the set point is the signal input set_point (cascade), not a time function
        self.setpoint_from_signal = (
            P["setpoint"] is None and "setpoint" not in self.signal_unit_values
        )

    # ---------------------------------------------------------------- ports
    def signal_inputs(self):
        ins = [self.SIGNAL_INPUTS[0]]
        if self.params["tracking"]:
            ins.append(self.SIGNAL_INPUTS[1])
        if self.setpoint_from_signal:
            ins.append(self.SIGNAL_INPUTS[2])
        return ins

    def signal_outputs(self):
        return [SignalPort("z", self.params["unit"], "limited output", variable="z")]

    @property
    def measured_unit(self) -> str:
        return getattr(self, "input_units", {}).get("measured", "1") or "1"

    @property
    def error_unit(self) -> str:
        u = self.measured_unit
        return "delta_K" if u == "K" else ("1" if u == "*" else u)

    # ------------------------------------------------------------ variables
    @property
    def has_d(self) -> bool:
        return self.params["T_d"] > 0

    def variables(self):
        check_set_point_unit(self)
        P = self.params
        unit = P["unit"]
        span_m = P["measured_span"] or P["measured_nominal"]
        out = [
            Variable("e", self.error_unit, span_m * 0.01, doc="control error"),
            Variable("m_p", unit, self.span_out, doc="proportional part"),
            # without an I part m_I is a bias that only tracking moves: a steady start
            # keeps it at integral0 (an accumulator) instead of leaving it undetermined
            Variable(
                "m_I",
                unit,
                self.span_out,
                doc="integral part",
                accumulator=P["T_i"] is None,
            ),
        ]
        if self.has_d:
            out += [
                Variable("x_f", self.error_unit, span_m * 0.01, doc="derivative filter state"),
                Variable("m_D", unit, self.span_out, doc="derivative part"),
            ]
        out += [
            Variable("v", unit, self.span_out, doc="demanded output m_p + m_I + m_D"),
            Variable("z", unit, self.span_out, doc="output"),
        ]
        return out

    def outputs(self):
        return [
            Output("setpoint", self.measured_unit, "set point, in the unit of the measured signal"),
            Output("z_min", self.params["unit"], "lower output limit"),
            Output("z_max", self.params["unit"], "upper output limit"),
        ]

    def output_values(self, t, x, xp):
        return [self.set_point_value(t, x), self.params["z_min"], self.params["z_max"]]

    def set_point_value(self, t, x) -> float:
        """The set point w [measured unit]: the signal input or the time function."""
        if self.setpoint_from_signal:
            return x["set_point"]
        return self.param_at("setpoint", t)

    # ------------------------------------------------------------ equations
    def _automatic(self, t) -> bool:
        return self.param_at("active", t) >= 0.5

    def equations(self):
        """The equations of the class doc (their residuals: ``row_values``)."""
        track = ("track",) if self.params["tracking"] else ()
        w = ("set_point",) if self.setpoint_from_signal else ()
        w_d = w if self.params["c_d"] != 0.0 else ()
        eqs = [
            Equation("error", y=("e", "measured", *w), doc="e = s (measured - w)"),
            Equation("proportional", y=("m_p", "e"), doc="m_p = Kp e"),
        ]
        if self.has_d:
            eqs += [
                Equation(
                    "filter",
                    y=("x_f", "measured", *w_d),
                    yp=("x_f",),
                    doc="(T_d/N) dx_f/dt = e_D - x_f",
                ),
                Equation(
                    "derivative", y=("m_D", "x_f", "measured", *w_d), doc="m_D = Kp N (e_D - x_f)"
                ),
            ]
        d = ("m_D",) if self.has_d else ()
        eqs += [
            Equation(
                "integral",
                y=("e", "z", "v", *track),
                yp=("m_I",),
                doc="dm_I/dt = Kp/T_i e + (z - v)/T_t (automatic), (z_track - v)/T_t (manual)",
            ),
            Equation("demand", y=("v", "m_p", "m_I", *d), doc="v = m_p + m_I + m_D"),
            Equation(
                "output",
                y=("z", "v", *(track if self.has_manual else ())),
                doc="z = v (free), z_max (high), z_min (low), z_track (manual)",
            ),
        ]
        return eqs

    def row_reads(self):
        """The names ``row_values`` reads (``Component.row_reads``)."""
        d = ("x_f", "m_D") if self.has_d else ()
        track = ("track",) if self.params["tracking"] else ()
        w = ("set_point",) if self.setpoint_from_signal else ()
        reads_yp = ("m_I", "x_f") if self.has_d else ("m_I",)
        return ("e", "measured", "m_p", "m_I", *d, "v", "z", *track, *w), reads_yp

    def row_values(self, t, v, vp, modes):
        """The equations of the class doc, in the order of ``equations()``, their
        residuals ([m] error and filter, [u] the parts and the output, [u/s] the
        integral), in automatic (mode ``modes["mode"]``) or manual:

          error         e - s (measured - w)
          proportional  m_p - Kp e
          filter        (T_d/N) dx_f/dt - (e_D - x_f)                    (T_d > 0)
          derivative    m_D - Kp N (e_D - x_f)                           (T_d > 0)
          integral      dm_I/dt - (Kp/T_i e + (z_a - v)/T_t)   automatic, anti_windup
                        (z_a = track with tracking, else z)
                        dm_I/dt - Kp/T_i e                     automatic, no anti-windup
                        (dm_I/dt without an I part)
                        dm_I/dt - (z_track - v)/T_t            manual
          demand        v - m_p - m_I - m_D                    (m_D = 0 without a D part)
          output        z - v (free), z - z_max (high), z - z_min (low), z - z_track (manual)
        """
        P, Kp, has_d, tracking = self.params, self.Kp, self.has_d, self.params["tracking"]
        e, measured, m_p, m_I = v[0], v[1], v[2], v[3]
        k = 6 if has_d else 4  # the position of v (the demand) in ``row_reads``
        x_f, m_D = (v[4], v[5]) if has_d else (0.0, 0.0)
        dem, z = v[k], v[k + 1]
        track = v[k + 2] if tracking else None
        w = v[-1] if self.setpoint_from_signal else self.param_at("setpoint", t)
        out = [e - self.sign * (measured - w), m_p - Kp * e]
        if has_d:
            N = P["N"]
            e_d = self._e_d(measured, w)
            out += [P["T_d"] / N * vp[1] - (e_d - x_f), m_D - Kp * N * (e_d - x_f)]
        if not self._automatic(t):
            z_track = track if tracking else self.param_at("z_manual", t)
            integral = vp[0] - (z_track - dem) / self.T_t
            output = z - z_track
        else:
            rate = Kp / P["T_i"] * e if P["T_i"] is not None else 0.0
            if P["anti_windup"] and P["T_i"] is not None:
                rate += ((track if tracking else z) - dem) / self.T_t
            integral = vp[0] - rate
            output = z - LIMITED.target(LIMITED.mode(modes), dem, P["z_min"], P["z_max"])
        return out + [integral, dem - m_p - m_I - m_D, output]

    def _e_d(self, measured, w) -> float:
        """e_D = s (measured - c_d w) [m], the D part's error."""
        return self.sign * (measured - self.params["c_d"] * w)

    # ------------------------------------------------------------- switches
    def reset_discrete_state(self, modes):
        LIMITED.reset(modes)

    @staticmethod
    def _mode(x):
        return LIMITED.mode(x.modes)

    def _upper(self, t, x, xp):
        if not self._automatic(t):
            return 1.0
        return LIMITED.upper(x["v"], self.params["z_max"], self._mode(x))

    def _lower(self, t, x, xp):
        if not self._automatic(t):
            return 1.0
        return LIMITED.lower(x["v"], self.params["z_min"], self._mode(x))

    def _toggle(self, which):
        def action(t, x, xp):
            LIMITED.toggle(x.modes, which)

        return action

    def switches(self):
        return [
            Switch("upper", self._upper, -1, self._toggle("high"), "enter/leave z = z_max"),
            Switch("lower", self._lower, -1, self._toggle("low"), "enter/leave z = z_min"),
        ]

    def init_discrete_state(self, t0, x, xp):
        P = self.params
        return LIMITED.start(x.modes, x["v"], P["z_min"], P["z_max"])

    def initial_guess(self, t0, x):
        P = self.params
        x["m_I"] = P["integral0"]
        x["e"] = 0.0
        x["m_p"] = 0.0
        x["v"] = P["integral0"]
        if self.has_d:
            x["x_f"] = self._e_d(x["measured"], self.set_point_value(t0, x))
            x["m_D"] = 0.0
        x["z"] = min(max(P["integral0"], P["z_min"]), P["z_max"])

    def free_at_rest(self, t0, x):
        """Saturated without back-calculation (anti_windup = false), the output is the
        limit and no equation reads the integral m_I: the steady start keeps it and
        solves its rate dm_I/dt = Kp/T_i e (``Component.free_at_rest``). With
        anti_windup the back-calculation term reads the demand v, so m_I is determined
        (at rest v - z_lim = T_t Kp e / T_i); without an I part m_I is an accumulator."""
        P = self.params
        if self._mode(x) == LIMITED.FREE or P["T_i"] is None or P["anti_windup"]:
            return ()
        return ("m_I",) if self._automatic(t0) else ()

    def design_values(self, t0, x):
        return {"opening": x["z"]}

    def steady_problems(self, t0, x):
        return output_range_problems(self, x)
