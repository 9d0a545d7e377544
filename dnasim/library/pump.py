"""Pump: a centrifugal pump with a quadratic head curve, affinity laws and an efficiency."""

from __future__ import annotations

import math

import numpy as np

from dnasim.core.errors import PlantError
from dnasim.library.control_valve import vapour_pressure
from dnasim.model.component import (
    Component,
    Equation,
    FluidPort,
    Output,
    Param,
    SignalPort,
    Switch,
    Variable,
    flow_through_ports,
    shaft_work_equations,
)
from dnasim.model.physics import (
    M_REG_REL,
    G,
    is_condensable,
    reverse_fraction,
    saturation_enthalpies,
    softplus,
    upwind_weight,
)

#: head [m] above the shut-off head that the cavitation switch function takes for
#: reverse flow (m <= -m_eps, blended by physics.reverse_fraction): a pump that does
#: not draw from its suction does not cavitate
NPSH_REVERSE_MARGIN = 10.0


class Pump(Component):
    """Centrifugal pump between ``inlet`` and ``outlet``, no storage.

    Symbols: m [kg/s] mass flow (inlet -> outlet positive), rho [kg/m3] the
    density of the fluid in the pump (below), Q = m/rho [m3/s] volume flow, r = n/n_0
    [-] the relative speed (parameter ``speed`` or signal input ``n``), H [m] head,
    eta [-] efficiency, g = 9.80665 m/s2, w the smooth max(m, 0) of the upwinding
    (``physics.upwind_weight``), sigma(m) [-] the reverse fraction: 0 for m >= 0,
    1 for m <= -m_eps, a C2 step between (``physics.reverse_fraction``; m_eps =
    1e-3 m_nominal).

      head      H = H0 r^2 + a r Q + b Q sqrt(Q^2 + Q_reg^2)                     [m]
                (affinity laws: H(Q, r) = r^2 H_1(Q/r) for the nominal-speed curve
                H_1(q) = H0 + a q + b q|q|; b < 0)
      pressure  p_out - p_in = rho g H                                            [Pa]
      density   rho = (1 - sigma) rho(p_in, h_in) + sigma rho(p_out, h_out)      [kg/m3]
      enthalpy  h_2 = h_in + softplus(p_out - p_in, dp_reg) / (rho eta)           [J/kg]
      reverse   h_1 = (1 - sigma) h_in + sigma h_out                             [J/kg]
      power     P = w(m) (h_2 - h_in) + w(-m) (h_1 - h_out)                       [W]
                (shaft power; = m dp/(rho eta) for m > m_eps, 0 for m < -m_eps)
      work      dW/dt = P      (W [J]: shaft work over the run, for energy balances)
      eta       eta = eta (constant), or eta_1(Q/r) from the table eta_Q, eta_values at
                nominal speed (affinity: similar points have equal efficiency),
                PCHIP-interpolated, held at the end values, and at least eta_min.

    The curve is given in one of three ways: ``H0`` with ``a``, ``b`` (coefficients);
    ``H0`` with ``H_nominal`` at ``Q_nominal`` (a = 0, b = (H_nominal - H0)/Q_nominal^2);
    or the points ``curve_Q`` [m3/s], ``curve_H`` [m] at nominal speed (least-squares
    quadratic H0 + a q + b q^2, exact through three points).

    Tabulated head (head_curve = "table", points curve_Q from 0 up, curve_H):
      H_1(q) = PCHIP through the points for 0 <= q <= q_e (the last point),
      H(Q, r) = r^2 H_1(Q/r)                                   0 <= Q <= r q_e
              = r^2 H_e + s_e r (Q - r q_e) + b D sqrt(D^2 + Q_reg^2),  D = Q - r q_e > 0
              = r^2 H_1(0) + s_0 r Q + b Q sqrt(Q^2 + Q_reg^2)         Q < 0
      (s_0, s_e [m s/m3] the table's end slopes, b the least-squares quadratic's
      curvature: beyond the table the curve continues as a parabola, so that the
      affinity law stays defined down to r = 0, where it is the same resistance.)

    No-flow and reverse flow: at Q = 0 the head is the shut-off head H0 r^2; the
    term b Q sqrt(Q^2 + Q_reg^2) (Q_reg = 1e-2 m_nominal/rho) keeps dH/dQ < 0 at
    Q = 0, so a pump against a closed valve or between two fixed pressures stays
    index 1. A stopped pump (r = 0) is the resistance p_out - p_in = rho g b Q|Q|
    in both directions. The pump holds suction fluid while it pumps or stands
    (m >= 0) and discharge fluid in reverse flow (m <= -m_eps): the density of the
    head is the suction's, so a dead-headed pump delivers its shut-off head
    p_in + rho_in g H0 r^2 whatever lies behind its discharge, and what leaves
    through the inlet, h_1, is the suction node's own enthalpy, so the
    regularisation's zero-flow exchange (w(0) = 3/16 m_eps both ways) carries no
    discharge water (heated by compression and losses) back into the suction; only
    real reverse flow carries the discharge node's enthalpy there (isenthalpic: no
    work is exchanged with reverse flow). Fluid leaving through the outlet carries
    h_2. The energy flows at the ports and P balance exactly: E_out - E_in = P
    (the term w(-m) (h_1 - h_out) is the exchange's share; at zero flow P =
    w(0) (h_2 - h_out), 0 when the discharge holds the delivery state). Why: with
    the plain upwind mean a deaerator suction at 150 degC and 5 bar (1.8 K
    subcooled) took the mean of its own and the discharge's enthalpy as a tripped
    feed pump's flow passed zero, reached saturation, and Newton failed; a pump
    against a shut feed valve used the mean of the suction's and a two-phase
    discharge's density and delivered 68 bar of its 131 bar shut-off head (issue
    20). When p_out < p_in (a stopped pump, or flow beyond the curve's run-out) the
    smooth max (softplus, width dp_reg) makes the flow isenthalpic instead of
    cooling it.

    NPSH (condensable media): the output NPSH_a [m] is the net positive suction
    head available at the suction node (p_in, h_in), with the velocity head when
    the suction nozzle's flow area ``A_suction`` is given (v = m/(rho_in A)):

      NPSH_a = (p_in - p_v(T_in)) / (rho_in g) + v^2/(2 g)        liquid inlet  [m]
             = v^2/(2 g) - (h_in - h'(p_in)) / g                  flashing inlet
      NPSH_r = r^2 NPSH_r_1(Q/r)     (affinity law; NPSH_r_1 at nominal speed: the
               number NPSH_r, or the curve NPSH_r_Q, NPSH_r_values, PCHIP, held at
               its ends; without either NPSH_r = 0: the check is on flashing)

    (p_v the vapour pressure at the suction temperature, IF97 for water; h' the
    enthalpy of saturated liquid; both forms are 0 at saturation, so NPSH_a is
    continuous and negative once the suction flashes.) The switch "cavitation",
    NPSH_a - NPSH_r + (H0 + 10 m) sigma(m) (a pump in reverse flow draws nothing
    from its suction), is located where it falls through zero: with cavitation =
    "stop" (default) the run stops there with a message naming the pump, the time,
    NPSH_a, NPSH_r and the suction state; with "warn" the message is a warning of
    the run (printed by ``dnasim run``, in report.html and ``Results.warnings``)
    and the run goes on. A pump that cavitates at the start stops the start
    ("stop") or warns. The node pressure is the static pressure at the suction
    flange: a suction vessel above the pump is a Pipe with dz < 0 before it.

    Shut-off heating (give ``M_casing``): the fluid in the pump is a mixed volume of
    constant mass M [kg] with its own enthalpy h_2 [J/kg] (and density rho(p_out, h_2)
    in the head), a differential variable,
    which leaves at the outlet (and at the inlet in reverse flow); the shaft power, including the
    losses P_0 r^3 that remain at zero flow (disk friction, recirculation; affinity
    law P ~ r^3), heats it:

      power     P = w(m) softplus(p_out - p_in, dp_reg)/(rho eta) + P_0 r^3          [W]
      energy    M dh_2/dt = w(m) (h_in - h_2) + w(-m) (h_out - h_1) + P               [W]
                (h_in, h_out the inlet and outlet nodes' h; w the smooth max(m, 0))

    With flow, h_2 relaxes in M/m seconds to h_in + P/m = h_in + dp/(rho eta) +
    P_0 r^3/m: the enthalpy rise P_shaft/m, regularised at zero flow by the mass M.
    Against a closed valve (m = 0) dh_2/dt = P_0 r^3/M [J/(kg s)], so the water in the
    pump warms at dT/dt = P_0 r^3/(M c_p) [K/s] until the flow resumes and carries
    the heat off. The ports' energy flows, P and the stored energy M h_2 balance
    exactly: E_in - E_out + P = M dh_2/dt. What leaves through the inlet is
    h_1 = (1 - sigma) h_in + sigma h_2 (suction water unless in reverse flow, as
    above), so the energy balance reads
    M dh_2/dt = w(m) (h_in - h_2) + w(-m) (h_out - h_1) + P. At zero flow the smooth
    upwind weight w(0) = 3/16 m_eps [kg/s] still exchanges casing water with the
    discharge node, a loss of w(0) (h_2 - h_out) [W], and adds w(0) dp/(rho eta)
    to P (2.6 W in tests/plants/pump_shutoff.toml). M_casing is the water in the casing; the
    casing's metal can be lumped in as the water mass of equal heat capacity
    C_metal/c_p [kg].
    """

    PARAMS = (
        Param("H0", "m", None, "shut-off head at nominal speed (Q = 0)", min=0.0),
        Param("a", "s/m2", 0.0, "linear coefficient of the head curve [m per m3/s]"),
        Param("b", "s2/m5", None, "quadratic coefficient of the head curve (< 0)"),
        Param("H_nominal", "m", None, "head at Q_nominal and nominal speed", min=0.0),
        Param("Q_nominal", "m3/s", None, "volume flow of the nominal point", min=0.0),
        Param(
            "curve_Q",
            "m3/s",
            None,
            "volume flows [m3/s] of head-curve points (nominal speed)",
            kind="array",
        ),
        Param("curve_H", "m", None, "heads [m] of the head-curve points", kind="array"),
        Param(
            "head_curve",
            "1",
            "quadratic",
            "the points as a least-squares quadratic, or a table (PCHIP)",
            kind="string",
            choices=("quadratic", "table"),
        ),
        Param(
            "speed",
            "1",
            None,
            "relative speed n/n_0 (otherwise from the signal input 'n')",
            min=0.0,
            time_function=True,
        ),
        Param("eta", "1", 0.8, "efficiency (when no table is given)", min=0.0, max=1.0),
        Param(
            "eta_Q",
            "m3/s",
            None,
            "volume flows [m3/s] of the efficiency table (nominal speed)",
            kind="array",
        ),
        Param(
            "eta_values", "1", None, "efficiencies [-] of the table", min=0.0, max=1.0, kind="array"
        ),
        Param("eta_min", "1", 0.05, "lower limit of the efficiency", min=1e-6, max=1.0),
        Param(
            "dp_reg",
            "delta_Pa",
            100.0,
            "width of the smooth max(dp, 0) in the enthalpy rise",
            min=0.0,
        ),
        Param("m_nominal", "kg/s", 1.0, "typical mass flow (scales and tolerances)", min=0.0),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
        Param(
            "M_casing",
            "kg",
            None,
            "mass of the fluid in the pump: a heated mixed volume (shut-off heating)",
            min=0.0,
        ),
        Param(
            "P_shutoff",
            "W",
            0.0,
            "shaft power at zero flow and nominal speed, P_0 (with M_casing)",
            min=0.0,
        ),
        Param(
            "A_suction",
            "m2",
            None,
            "flow area of the suction nozzle: adds the velocity head to NPSH_a",
            min=0.0,
        ),
        Param("NPSH_r", "m", None, "NPSH required at nominal speed (a number)", min=0.0),
        Param(
            "NPSH_r_Q",
            "m3/s",
            None,
            "volume flows [m3/s] of an NPSH-required curve (nominal speed)",
            kind="array",
        ),
        Param("NPSH_r_values", "m", None, "NPSH required [m] at NPSH_r_Q", min=0.0, kind="array"),
        Param(
            "cavitation",
            "1",
            "stop",
            "when NPSH_a falls below NPSH_r (or the suction flashes): stop the run, or warn",
            kind="string",
            choices=("stop", "warn"),
        ),
    )
    FLUID_PORTS = (
        FluidPort("inlet", "inlet", "m", "resistance", "suction"),
        FluidPort("outlet", "outlet", "m", "resistance", "discharge (h_2 on forward flow)"),
    )
    SIGNAL_INPUTS = (SignalPort("n", "1", "relative speed n/n_0 (when 'speed' is not given)"),)
    SIGNAL_OUTPUTS = (
        SignalPort("P", "W", "shaft power", variable="P"),
        SignalPort("H", "m", "head", variable="H"),
    )

    # ------------------------------------------------------------------ set-up
    def setup(self):
        P = self.params
        self.speed_from_signal = P["speed"] is None
        #: the fluid in the pump is a heated volume (M_casing given): h_2 is a state
        self.casing = P["M_casing"] is not None and P["M_casing"] > 0.0
        if P["P_shutoff"] > 0.0 and not self.casing:
            raise PlantError(
                f"component '{self.name}' (Pump): P_shutoff needs M_casing > 0 kg (the water "
                "in the pump that the shut-off power heats)"
            )
        self.H0, self.a, self.b = self._curve()
        self._head_table = None
        if P["head_curve"] == "table":
            self._head_table = self._table()
        if not self.b < 0:
            raise PlantError(
                f"component '{self.name}' (Pump): the head curve's quadratic coefficient b = "
                f"{self.b:g} s2/m5 must be < 0 (the head must fall with the flow)"
            )
        self._npsh_r = self._npsh_curve()
        self._eta_table = None
        if (P["eta_Q"] is None) != (P["eta_values"] is None):
            raise PlantError(
                f"component '{self.name}' (Pump): give both 'eta_Q' and 'eta_values' for an "
                "efficiency table"
            )
        if P["eta_Q"] is not None:
            q, e = np.asarray(P["eta_Q"]), np.asarray(P["eta_values"])
            if q.size != e.size or q.size < 2 or np.any(np.diff(q) <= 0):
                raise PlantError(
                    f"component '{self.name}' (Pump): 'eta_Q' must rise strictly and have as "
                    "many (at least 2) entries as 'eta_values'"
                )
            from scipy.interpolate import PchipInterpolator

            self._eta_table = (PchipInterpolator(q, e), q[0], q[-1])
        elif P["eta"] <= 0:
            raise PlantError(f"component '{self.name}' (Pump): parameter 'eta' must be > 0")

    def _npsh_curve(self):
        """NPSH_r_1(q) [m] at nominal speed: None, a number, or a PCHIP of the points
        NPSH_r_Q, NPSH_r_values held at its end values."""
        P = self.params
        name = f"component '{self.name}' (Pump)"
        if (P["NPSH_r_Q"] is None) != (P["NPSH_r_values"] is None):
            raise PlantError(f"{name}: give both 'NPSH_r_Q' and 'NPSH_r_values'")
        if P["NPSH_r_Q"] is not None:
            if P["NPSH_r"] is not None:
                raise PlantError(f"{name}: give NPSH_r as a number or as a curve, not both")
            q, v = np.asarray(P["NPSH_r_Q"]), np.asarray(P["NPSH_r_values"])
            if q.size != v.size or q.size < 2 or np.any(np.diff(q) <= 0):
                raise PlantError(
                    f"{name}: 'NPSH_r_Q' must rise strictly and have as many (at least 2) "
                    "entries as 'NPSH_r_values'"
                )
            from scipy.interpolate import PchipInterpolator

            return (PchipInterpolator(q, v), float(q[0]), float(q[-1]))
        return P["NPSH_r"]

    def _curve(self):
        """(H0 [m], a [s/m2], b [s2/m5]) from whichever way the curve was given."""
        P = self.params
        name = f"component '{self.name}' (Pump)"
        if P["curve_Q"] is not None or P["curve_H"] is not None:
            if P["curve_Q"] is None or P["curve_H"] is None:
                raise PlantError(f"{name}: give both 'curve_Q' and 'curve_H'")
            q, h = np.asarray(P["curve_Q"]), np.asarray(P["curve_H"])
            if q.size != h.size or q.size < 3 or np.unique(q).size < 3:
                raise PlantError(
                    f"{name}: 'curve_Q' and 'curve_H' need the same number (at least 3) of "
                    "points at distinct flows"
                )
            b, a, H0 = np.polyfit(q, h, 2)
            return float(H0), float(a), float(b)
        if P["H0"] is None:
            raise PlantError(
                f"{name}: give the head curve: H0 with b (and a), H0 with H_nominal and "
                "Q_nominal, or the points curve_Q, curve_H"
            )
        if P["b"] is not None:
            return P["H0"], P["a"], P["b"]
        if P["H_nominal"] is None or P["Q_nominal"] is None:
            raise PlantError(f"{name}: with H0 give b, or H_nominal and Q_nominal")
        return P["H0"], 0.0, (P["H_nominal"] - P["H0"]) / P["Q_nominal"] ** 2

    def _table(self):
        """(PCHIP H_1, q_e [m3/s], H_e [m], s_0, s_e [m s/m3]) of a tabulated head curve."""
        name = f"component '{self.name}' (Pump)"
        if self.params["curve_Q"] is None:
            raise PlantError(f"{name}: head_curve = 'table' needs the points curve_Q, curve_H")
        q, h = np.asarray(self.params["curve_Q"]), np.asarray(self.params["curve_H"])
        if q[0] != 0.0 or np.any(np.diff(q) <= 0):
            raise PlantError(
                f"{name}: the head table's curve_Q must start at 0 (shut-off) and rise strictly"
            )
        from scipy.interpolate import PchipInterpolator

        f = PchipInterpolator(q, h)
        d = f.derivative()
        return f, float(q[-1]), float(h[-1]), float(d(0.0)), float(d(q[-1]))

    def fluid_ports(self):
        ports = flow_through_ports(self.m_eps, "h_2")
        # reverse flow leaves through the inlet with h_1 (``reverse`` equation)
        ports[0] = FluidPort(
            "inlet", "inlet", "m", "resistance", h_out="h_1", h_source=False, m_eps=self.m_eps
        )
        return ports

    def signal_inputs(self):
        return list(self.SIGNAL_INPUTS) if self.speed_from_signal else []

    def variables(self):
        mn = self.params["m_nominal"]
        return [
            Variable("m", "kg/s", mn, doc="mass flow, inlet -> outlet"),
            Variable("H", "m", max(self.H0, 1.0), doc="head"),
            Variable(
                "h_2",
                "J/kg",
                1e5,
                doc="enthalpy of the fluid leaving at the outlet (with M_casing: in the pump)",
            ),
            Variable("P", "W", max(mn * G * self.H0, 1.0), doc="shaft power"),
            Variable(
                "W",
                "J",
                max(mn * 1e5, 1.0),
                doc="shaft work done on the fluid, integral of P dt",
                accumulator=True,
            ),
            Variable(
                "h_1",
                "J/kg",
                1e5,
                doc="enthalpy of the fluid leaving through the inlet (reverse flow)",
            ),
        ]

    def equations(self):
        n = self.speed_reads()
        nodes = ("inlet.p", "inlet.h", "outlet.p", "outlet.h")
        if self.casing:
            return self._casing_equations(n, nodes)
        return (
            self._head_equations(n, nodes)
            + [
                Equation(
                    "enthalpy",
                    y=("h_2", "m") + nodes + n,
                    unit="J/kg",
                    doc="h_2 = h_in + softplus(p_out - p_in)/(rho eta)",
                    residual=self._enthalpy,
                ),
                Equation(
                    "power",
                    y=("P", "m", "h_2", "h_1", "inlet.h", "outlet.h"),
                    unit="W",
                    doc="P = w(m) (h_2 - h_in) + w(-m) (h_1 - h_out)",
                    residual=self._power,
                ),
            ]
            + shaft_work_equations(self, "inlet.h", "h_2")[1:]  # work: dW/dt = P
            + [self._reverse_equation("outlet.h")]
        )

    def _reverse_equation(self, h_back):
        """h_1 = sigma(m) h_back + (1 - sigma(m)) h_in: what leaves through the inlet."""
        return Equation(
            "reverse",
            y=("h_1", "m", "inlet.h", h_back),
            unit="J/kg",
            doc=f"h_1 = sigma(m) {h_back} + (1 - sigma(m)) h_in",
            residual=lambda t, x, xp: x["h_1"] - self.reverse_enthalpy(x, x[h_back]),
        )

    def reverse_enthalpy(self, x, h_back) -> float:
        """h_1 [J/kg]: h_back (the discharge node's h; with the casing, h_2) for
        m <= -m_eps, the suction node's own h for m >= 0 (``physics.reverse_fraction``)."""
        s = reverse_fraction(x["m"], self.m_eps)
        return s * h_back + (1.0 - s) * x["inlet.h"]

    def _power(self, t, x, xp):
        m = x["m"]
        w = float(upwind_weight(m, self.m_eps))
        w_back = float(upwind_weight(-m, self.m_eps))
        return x["P"] - w * (x["h_2"] - x["inlet.h"]) - w_back * (x["h_1"] - x["outlet.h"])

    def _head_equations(self, n, nodes):
        """The head curve and the pressure rise; nodes: the variables rho is read from."""
        return [
            Equation(
                "head",
                y=("H", "m") + nodes + n,
                unit="m",
                doc="H = H0 r^2 + a r Q + b Q sqrt(Q^2 + Q_reg^2)",
                residual=self._head,
            ),
            Equation(
                "pressure",
                y=("H", "m") + nodes,
                unit="Pa",
                doc="p_out - p_in = rho g H",
                residual=self._pressure,
            ),
        ]

    def _casing_equations(self, n, nodes):
        """head, pressure, power and energy with the heated casing volume (docstring)."""
        nodes = (*nodes, "h_2")  # the density is the casing fluid's
        head = self._head_equations(n, nodes)
        M = self.params["M_casing"]
        return (
            head
            + [
                Equation(
                    "power",
                    y=("P", "m") + nodes + n,
                    unit="W",
                    doc="P = w(m) softplus(p_out - p_in)/(rho eta) + P_0 r^3",
                    residual=lambda t, x, xp: x["P"] - self.shaft_power(t, x),
                ),
                Equation(
                    "energy",
                    y=("h_2", "m", "P", "h_1", "inlet.h", "outlet.h"),
                    yp=("h_2",),
                    unit="W",
                    doc=f"{M:g} dh_2/dt = w(m) (h_in - h_2) + w(-m) (h_out - h_1) + P",
                    residual=self._casing_energy,
                ),
            ]
            + shaft_work_equations(self, "inlet.h", "h_2")[1:]  # work: dW/dt = P
            + [self._reverse_equation("h_2")]
        )

    def shaft_power(self, t, x) -> float:
        """P [W] with the casing: w(m) softplus(dp, dp_reg)/(rho eta) + P_0 r^3."""
        rho = self.density(x)
        r = self.speed(t, x)
        eta = self.efficiency(x["m"] / rho, r)
        dp = float(softplus(x["outlet.p"] - x["inlet.p"], self.params["dp_reg"]))
        w = float(upwind_weight(x["m"], self.m_eps))
        return w * dp / (rho * eta) + self.params["P_shutoff"] * r**3

    def _casing_energy(self, t, x, xp):
        m, h = x["m"], x["h_2"]
        w_in = float(upwind_weight(m, self.m_eps))
        w_back = float(upwind_weight(-m, self.m_eps))
        gain = w_in * (x["inlet.h"] - h) + w_back * (x["outlet.h"] - x["h_1"]) + x["P"]
        return self.params["M_casing"] * xp["h_2"] - gain

    def outputs(self):
        out = [Output("T_2", "K", "temperature at h_2 and the discharge pressure")]
        if self.npsh_checked:
            out.append(Output("NPSH_a", "m", "net positive suction head available"))
            if self._npsh_r is not None:
                out.append(Output("NPSH_r", "m", "net positive suction head required"))
        return out

    def output_values(self, t, x, xp):
        out = [float(self.medium.state(x["outlet.p"], x["h_2"]).T)]
        if self.npsh_checked:
            out.append(self.npsh_available(x))
            if self._npsh_r is not None:
                out.append(self.npsh_required(t, x))
        return out

    # ------------------------------------------------------------------ NPSH
    @property
    def npsh_checked(self) -> bool:
        """True for a condensable medium (a liquid that can flash at the suction)."""
        return self.medium is None or is_condensable(self.medium)

    def suction_state(self, x):
        """(rho [kg/m3], T [K], T_sat [K] or nan, h' [J/kg] or nan) at the suction node."""
        medium = self.medium
        p, h = x["inlet.p"], x["inlet.h"]
        st = medium.state(p, h)
        hl, _ = saturation_enthalpies(medium, p)
        hl = float(hl[0])
        T_sat = float(medium.state(p, hl).T) if math.isfinite(hl) else math.nan
        return float(st.rho), float(st.T), T_sat, hl

    def npsh_available(self, x) -> float:
        """NPSH_a [m] at the suction node (p_in, h_in); see the class doc."""
        p, h = x["inlet.p"], x["inlet.h"]
        rho, T, _, hl = self.suction_state(x)
        A = self.params["A_suction"]
        v = x["m"] / (rho * A) if A else 0.0
        head = v * v / (2.0 * G)
        if math.isfinite(hl) and h > hl:  # flashing: the enthalpy above h' as head
            return head - (h - hl) / G
        p_v, _ = vapour_pressure(self.medium, T)
        return (p - p_v) / (rho * G) + head

    def npsh_required(self, t, x) -> float:
        """NPSH_r(Q, r) = r^2 NPSH_r_1(Q/r) [m] (affinity law); 0 without a given NPSH_r."""
        f = self._npsh_r
        if f is None:
            return 0.0
        r = self.speed(t, x)
        if not isinstance(f, tuple):
            return float(f) * r * r
        curve, q0, q1 = f
        rho = self.density(x)
        q = min(max(x["m"] / rho / max(r, 1e-3), q0), q1)
        return float(curve(q)) * r * r

    def cavitation_margin(self, t, x) -> float:
        """NPSH_a - NPSH_r [m] for forward flow, blended into H0 + 10 m for reverse flow
        (w = physics.reverse_fraction(m)): (1 - w)(NPSH_a - NPSH_r) + w (H0 + 10 m). A
        pump that is flowed through backwards draws nothing from its suction and does
        not cavitate, however hot the fluid at its inlet node (it came from the
        discharge side: a stopped feed pump back-fed by its drum)."""
        w = reverse_fraction(x["m"], self.m_eps)
        forward = self.npsh_available(x) - self.npsh_required(t, x)
        return (1.0 - w) * forward + w * (self.H0 + NPSH_REVERSE_MARGIN)

    def cavitation_message(self, t, x) -> str:
        """The plain text of a cavitating pump at t, from the values in x."""
        a, r = self.npsh_available(x), self.npsh_required(t, x)
        _, T, T_sat, _ = self.suction_state(x)
        p = x["inlet.p"]
        if a <= 0.0:
            what = "the suction flashes (NPSH_a <= 0: the inlet is at or above saturation)"
        else:
            what = "the NPSH available fell below the NPSH required"
        sat = f" (saturation {T_sat - 273.15:.2f} °C)" if math.isfinite(T_sat) else ""
        given = "" if self._npsh_r is not None else " (none given)"
        text = (
            f"pump '{self.name}' (Pump): cavitation at t = {t:.6g} s: {what}: NPSH_a = "
            f"{a:.4f} m, NPSH_r = {r:.4f} m{given} at {x['m']:.4g} kg/s; suction {p / 1e5:.6g} "
            f"bar, {T - 273.15:.2f} °C{sat}. Raise the suction head (a vessel above the "
            "pump: a suction pipe with dz < 0) or the subcooling of the suction"
        )
        if self.params["cavitation"] == "stop":
            text += ', or give cavitation = "warn" to go on'
        return text

    def switches(self):
        if not self.npsh_checked:
            return []
        last = {}

        def g(t, x, xp):
            last["t"], last["x"] = t, {k: x[k] for k in self._npsh_reads()}
            margin = self.cavitation_margin(t, x)
            # warn mode: while cavitating the switch watches the recovery (g = -margin),
            # so that each crossing toggles the mode and moves g to its positive side
            return -margin if x.modes.get("cavitating") else margin

        def message(t):
            x = last.get("x")
            return self.cavitation_message(t, x) if x is not None else None

        def warn(t, x, xp):  # cavitation = "warn": the message at the located crossing
            if x.modes.get("cavitating"):  # NPSH_a rose above NPSH_r again
                x.modes["cavitating"] = False
                return
            x.modes["cavitating"] = True
            text = self.cavitation_message(t, x)
            warnings = x.modes.setdefault("warnings", [])
            if text not in warnings:  # the action of one crossing may run twice
                warnings.append(text)

        stop = self.params["cavitation"] == "stop"
        return [
            Switch(
                "cavitation",
                g,
                direction=-1,
                action=None if stop else warn,
                terminal=stop,
                notice=not stop,
                message=message if stop else None,
                doc="NPSH_a - NPSH_r [m] (+ margin for reverse flow): falls through 0 (with "
                'cavitation = "warn": its negative while the pump cavitates, the recovery)',
            )
        ]

    def _npsh_reads(self):
        n = self.speed_reads()
        extra = ("outlet.p", "outlet.h") + (("h_2",) if self.casing else ())
        return ("m", "inlet.p", "inlet.h") + extra + n

    def init_discrete_state(self, t0, x, xp):
        """A pump that cavitates at the start: PlantError (cavitation = "stop"), or a
        warning in its modes (``modes["warnings"]``: ``System.warnings``)."""
        if self.npsh_checked and self.cavitation_margin(t0, x) < 0.0:
            text = self.cavitation_message(t0, x).replace(
                "cavitation at", "cavitates at the start,"
            )
            text = text.replace("fell below", "is below")
            if self.params["cavitation"] == "stop":
                raise PlantError(text)
            warnings = x.modes.setdefault("warnings", [])
            if text not in warnings:  # the start may try its modes several times
                warnings.append(text)
            if not x.modes.get("cavitating"):
                x.modes["cavitating"] = True  # the switch now watches the recovery
        return False

    # --------------------------------------------------------------- physics
    def speed_reads(self) -> tuple[str, ...]:
        """The local names the relative speed is read from: ("n",) for the signal
        input, () for the parameter (a subclass with a speed state: its own)."""
        return ("n",) if self.speed_from_signal else ()

    def speed(self, t, x):
        """Relative speed r = n/n_0 [-]."""
        return x["n"] if self.speed_from_signal else self.param_at("speed", t)

    def density(self, x):
        """Density of the fluid in the pump [kg/m3]: the suction's for m >= 0, the
        discharge node's for m <= -m_eps, blended by sigma(m) between (class doc);
        with the casing, rho(p_out, h_2), the casing water's at the delivery pressure
        (as T_2). Why not blended there: against a closed valve the casing water is
        hotter than the suction, and a density blended across the flow band |m| <
        m_eps makes p_out - p_in = rho g H rise with m near m = 0 (14 K: +2.7e5 Pa
        per kg/s against the curve's -200), so the reopening valve found no unique
        flow (Newton diverged). Why at p_out: h_2 holds the enthalpy rise of
        compression and losses, and a 150 degC deaerator suction, 1.8 K subcooled,
        is below that rise from saturation: at p_in the casing water was two-phase,
        the head fell to 1/3 and the pump never opened its check valve."""
        medium = self.medium
        if self.casing:
            return float(medium.state(x["outlet.p"], x["h_2"]).rho)
        rho_in = float(medium.state(x["inlet.p"], x["inlet.h"]).rho)
        s = reverse_fraction(x["m"], self.m_eps)
        if s == 0.0:
            return rho_in
        rho_out = float(medium.state(x["outlet.p"], x["outlet.h"]).rho)
        return s * rho_out + (1.0 - s) * rho_in

    def head(self, Q, r, rho):
        """H(Q, r) [m] at volume flow Q [m3/s], relative speed r, density rho [kg/m3]."""
        Q_reg = M_REG_REL * self.params["m_nominal"] / rho
        b = self.b
        if self._head_table is None:
            return self.H0 * r * r + self.a * r * Q + b * Q * np.sqrt(Q * Q + Q_reg * Q_reg)
        f, q_e, H_e, s_0, s_e = self._head_table
        if Q < 0.0:
            return r * r * float(f(0.0)) + s_0 * r * Q + b * Q * math.sqrt(Q * Q + Q_reg * Q_reg)
        D = Q - r * q_e
        if D > 0.0:
            return r * r * H_e + s_e * r * D + b * D * math.sqrt(D * D + Q_reg * Q_reg)
        return r * r * float(f(Q / r)) if r > 0.0 else 0.0

    def efficiency(self, Q, r):
        """eta(Q, r) [-]: constant, or the table at the similar point Q/r."""
        eta_min = self.params["eta_min"]
        if self._eta_table is None:
            return max(self.params["eta"], eta_min)
        f, q0, q1 = self._eta_table
        q = min(max(Q / max(r, 1e-3), q0), q1)
        return max(float(f(q)), eta_min)

    def _head(self, t, x, xp):
        rho = self.density(x)
        return x["H"] - self.head(x["m"] / rho, self.speed(t, x), rho)

    def _pressure(self, t, x, xp):
        return x["outlet.p"] - x["inlet.p"] - self.density(x) * G * x["H"]

    def _enthalpy(self, t, x, xp):
        rho = self.density(x)
        eta = self.efficiency(x["m"] / rho, self.speed(t, x))
        dp = float(softplus(x["outlet.p"] - x["inlet.p"], self.params["dp_reg"]))
        return x["h_2"] - x["inlet.h"] - dp / (rho * eta)

    def design_values(self, t0, x):
        """Shaft power into the fluid P [W] and the efficiency at the operating point."""
        out = {"m": x["m"], "power": x["P"]}
        try:
            rho = self.density(x)
            out["efficiency"] = self.efficiency(x["m"] / rho, self.speed(t0, x))
        except Exception:  # noqa: BLE001 - a table value, not a residual
            pass
        return out

    def guess_nodes(self, t0):
        """Discharge pressure guess [Pa]: 1 bar plus the head at m_nominal with cold water
        (1000 kg/m3), so that the nodes downstream are not guessed at the suction
        pressure (a feed line guessed at condenser pressure starts as steam)."""
        rho = 1000.0
        H = self.head(self.params["m_nominal"] / rho, 1.0, rho)
        return {"outlet": (1e5 + rho * G * max(H, 0.0), None)}

    def initial_guess(self, t0, x):
        mn = self.params["m_nominal"]
        r = self.param_at("speed", t0) if not self.speed_from_signal else 1.0
        try:
            rho = self.medium.state(x["inlet.p"], x["inlet.h"]).rho
        except Exception:
            rho = 1000.0
        H = self.head(mn / rho, r, rho)
        x["m"] = mn
        x["H"] = H
        dh = max(rho * G * H, 0.0) / (rho * self.efficiency(mn / rho, r))
        x["h_2"] = x["inlet.h"] + dh
        x["P"] = mn * dh
        if self.casing:
            x["P"] += self.params["P_shutoff"] * r**3
            x["h_2"] += self.params["P_shutoff"] * r**3 / mn
        x["W"] = 0.0
        x["h_1"] = x["inlet.h"]
        # the discharge node: the pump's pressure rise on the suction guess
        x["outlet.p"] = max(x["inlet.p"] + rho * G * H, x["inlet.p"])
        x["outlet.h"] = x["h_2"]
