"""Valve: flow through a restriction, m = C z sqrt(p_in - p_out) (seed eq. 10.13f)."""

from __future__ import annotations

from dnasim.core.errors import ResidualDomainError
from dnasim.model.component import (
    Component,
    Equation,
    FluidPort,
    Param,
    SignalPort,
    Variable,
    flow_through_ports,
)
from dnasim.model.physics import upwind_mean, valve_flow


class Valve(Component):
    """Valve with opening z from the signal input ``z`` or the parameter ``opening``.

      flow      m = C z_e (p_in - p_out) / ((p_in - p_out)^2 + dp_reg^2)^(1/4)
                  (= C z_e sqrt(p_in - p_out) for p_in - p_out >> dp_reg; odd in the
                  pressure difference, so reverse flow gives m < 0; finite slope at 0)
      z_e       = leakage + (1 - leakage) z
      density   with ``rho_nominal`` given: C -> C sqrt(rho_1/rho_nominal), rho_1 [kg/m3]
                the density of the upstream state (inside the two-phase dome the
                homogeneous mixture's; a smooth upwind mean of the two nodes'
                densities by dp over dp_reg): m = C z_e sqrt(rho_1/rho_nominal) g(dp),
                the Kv law with the actual inlet density. C is the flow coefficient at
                the density rho_nominal (e.g. the drain's condensate), and steam or a
                steam-water mixture passes less mass, by sqrt(rho_1/rho_nominal) (no
                choking or flashing: see ``DrainValve`` for those)

    The mass flow m [kg/s] is the same at both ports (no storage). Throttling is
    isenthalpic in both directions: fluid leaving through the outlet carries the
    inlet node's enthalpy, fluid leaving through the inlet (reverse flow) the
    outlet node's. The energy flows at the two ports cancel exactly.

    The parameter ``opening`` must lie in [0, 1]. A signal input z is used as
    given, not clipped: limit the driving controller's output to [0, 1]
    (PIController z_min, z_max; its defaults). Clipping inside the valve was tried
    and rejected: a flat clip makes the steady-state Jacobian singular as soon as
    a Newton iterate leaves [0, 1] (dm/dz = 0), and a clip with a small residual
    slope lets Newton find non-physical steady states (openings of several
    hundred, spray lines running backwards). A closed valve (z = 0) passes the
    leakage flow ``leakage`` C sqrt(dp): with the default 1e-6 it is a millionth
    of the full-open flow, and dm/dp stays > 0, so that a node between the closed
    valve and another volume-less component (a second valve, a mass-flow source)
    still has an equation for its pressure and the plant stays index 1.
    """

    PARAMS = (
        Param("C", "kg/(s.Pa0.5)", doc="flow coefficient", min=0.0),
        Param(
            "opening",
            "1",
            None,
            "fixed opening z in [0, 1] (otherwise from the signal input 'z')",
            min=0.0,
            max=1.0,
            time_function=True,
        ),
        Param(
            "leakage",
            "1",
            1e-6,
            "flow coefficient of the closed valve, as a fraction of C",
            min=0.0,
            max=1.0,
        ),
        Param(
            "dp_reg", "delta_Pa", 10.0, "regularisation pressure difference near dp = 0", min=0.0
        ),
        Param(
            "rho_nominal",
            "kg/m3",
            None,
            "density at which C holds: makes the flow follow the inlet density (drains)",
            min=0.0,
        ),
        Param("m_nominal", "kg/s", 1.0, "typical mass flow (scales and tolerances)", min=0.0),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    FLUID_PORTS = (
        FluidPort("inlet", "inlet", "m", "resistance", "fluid in", h_out="outlet.h"),
        FluidPort("outlet", "outlet", "m", "resistance", "fluid out", h_out="inlet.h"),
    )
    SIGNAL_INPUTS = (SignalPort("z", "1", "opening (when the parameter 'opening' is not given)"),)

    def setup(self):
        self.opening_from_signal = self.params["opening"] is None
        #: the flow follows the upstream density (parameter rho_nominal)
        self.density_aware = self.params["rho_nominal"] is not None

    def fluid_ports(self):
        return flow_through_ports(self.m_eps, "inlet.h")

    def signal_inputs(self):
        return list(self.SIGNAL_INPUTS) if self.opening_from_signal else []

    def variables(self):
        return [Variable("m", "kg/s", self.params["m_nominal"], doc="mass flow")]

    def equations(self):
        """The flow equation of the class doc (its residual: ``row_values``)."""
        return [
            Equation(
                "flow",
                y=self.row_reads()[0],
                unit="kg/s",
                doc="m = C z_eff sqrt(dp) (regularised near dp = 0)"
                + (", C times sqrt(rho_1/rho_nominal)" if self.density_aware else ""),
            )
        ]

    def effective_opening(self, t, z_signal=None) -> float:
        """z_e = leakage + (1 - leakage) z [1], z the signal input's value z_signal or
        the parameter ``opening`` at t."""
        z = z_signal if self.opening_from_signal else self.param_at("opening", t)
        leak = self.params["leakage"]
        return leak + (1.0 - leak) * z

    def opening(self, t, x):
        """z_e [1] (``effective_opening``) with the signal input's value from x."""
        return self.effective_opening(t, x["z"] if self.opening_from_signal else None)

    def row_reads(self):
        """The names ``row_values`` reads (``Component.row_reads``)."""
        z = ("z",) if self.opening_from_signal else ()
        rho = ("inlet.h", "outlet.h") if self.density_aware else ()
        return ("m", "inlet.p", "outlet.p") + z + rho, ()

    def row_values(self, t, v, vp, modes):
        """The equation of the class doc, its residual [kg/s]:
        flow  m - C z_e (p_in - p_out) / ((p_in - p_out)^2 + dp_reg^2)^(1/4)."""
        m, p_in, p_out = v[0], v[1], v[2]
        z_e = self.effective_opening(t, v[3] if self.opening_from_signal else None)
        C = self.params["C"]
        if self.density_aware:
            C *= self.density_factor(p_in, v[-2], p_out, v[-1])
        return [m - valve_flow(C, z_e, p_in - p_out, self.params["dp_reg"])]

    def density_factor(self, p_in, h_in, p_out, h_out) -> float:
        """sqrt(rho_1/rho_nominal) [-], rho_1 [kg/m3] the smooth upwind mean of the
        densities at the inlet (p_in [Pa], h_in [J/kg]) and outlet node by dp."""
        rho_in = self.medium.state(p_in, h_in).rho
        rho_out = self.medium.state(p_out, h_out).rho
        rho1 = float(upwind_mean(p_in - p_out, rho_in, rho_out, self.params["dp_reg"]))
        return (rho1 / self.params["rho_nominal"]) ** 0.5

    def design_values(self, t0, x):
        z = x["z"] if self.opening_from_signal else self.param_at("opening", t0)
        return {"m": x["m"], "opening": z}

    def initial_guess(self, t0, x):
        dp = x["inlet.p"] - x["outlet.p"]
        z = self.opening(t0, x) if not self.opening_from_signal else 0.5
        C = self.params["C"]
        if self.density_aware:
            try:
                C *= self.density_factor(x["inlet.p"], x["inlet.h"], x["outlet.p"], x["outlet.h"])
            except ResidualDomainError:  # a first guess outside the medium's range: C as given
                pass
        x["m"] = valve_flow(C, z, dp, self.params["dp_reg"])
