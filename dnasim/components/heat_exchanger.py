"""HeatExchanger: counter- or parallel-flow, lumped in n_sections, with wall heat
capacity and per-side flow-dependent heat transfer coefficients."""

from __future__ import annotations

import numpy as np

from dnasim.components.base import Component, Equation, FluidPort, Output, Param, Variable
from dnasim.components.channel import Channel
from dnasim.components.physics import (
    DT_Q_NOMINAL,
    M_REG_REL,
    has_phase_branches,
    is_condensable,
)
from dnasim.errors import PlantError


class HeatExchanger(Component):
    """Heat exchanger: a hot and a cold channel of n_sections volumes each, sharing
    a wall. Hot section i faces cold section n-1-i (flow = "counter", default) or
    cold section i (flow = "parallel"). With gas on one side and water on the
    other (media per side: hot_medium, cold_medium, or from the nodes) it is an
    economiser, an evaporator or a superheater.

    Each channel is a series of volumes as in ``Pipe`` (prefix hot_ / cold_;
    ``dnasim.components.channel``): mass, energy, density, internal_energy, heat,
    momentum per volume and the outlet pressure tie, with energy upwind of the
    actual flow (either direction), U = M u per volume (mixed volumes), and
      heat      Q_side[i] = kA_side/n LMTD(T_a - T_w, T_i - T_w)   (fluid -> wall)
    and the wall, section i (C_i = C_wall/n):
      wall[i]   C_i dT_w[i]/dt = hot_Q[i] + cold_Q[j(i)],  j = n-1-i (counter), i (parallel)

    Per-side heat transfer coefficient with nominal-point scaling
    (``dnasim.components.walls.flow_scaled_kA``; alpha ~ m^0.8 for turbulent flow):
      kA_side(m) = side_kA (sqrt(m^2 + m_reg^2)/side_m_kA)^side_kA_exponent
    with m the section's mean face flow, side_m_kA the flow at which side_kA
    holds (default m_nominal); side_kA_exponent = 0 (default) keeps kA constant.

    Friction per side, per section: with side_k given, dp = k/n m sqrt(m^2 + m_reg^2)/rho;
    otherwise the nominal-point law dp = side_dp_nominal/n m sqrt(m^2 + m_reg^2)/m_nominal^2
    (side_dp_nominal [Pa] is the pressure drop of the side at m_nominal, default
    0.1 bar). A side without friction (k = 0 or dp_nominal = 0) joins storage
    volumes with no resistance: index 2, reported by ``dnasim check``.

    Outlets are storage volumes (lead them to a resistance).
    Given start: fluid temperatures hot_T0, cold_T0; wall at their mean.
    Balances: d(sum M)/dt = inflows - outflows; d(U_hot + U_cold + C_wall T_w)/dt =
    sum of the four port energy flows (no heat leaves the component).
    """

    PARAMS = (
        Param("hot_V", "m3", doc="hot side volume", min=0.0),
        Param("cold_V", "m3", doc="cold side volume", min=0.0),
        Param("hot_kA", "W/K", doc="hot side heat transfer coefficient times area", min=0.0),
        Param("cold_kA", "W/K", doc="cold side heat transfer coefficient times area", min=0.0),
        Param("hot_k", "1/m4", None, "hot side friction coefficient (dp = k m|m|/rho)", min=0.0),
        Param("cold_k", "1/m4", None, "cold side friction coefficient (dp = k m|m|/rho)", min=0.0),
        Param(
            "hot_dp_nominal",
            "delta_Pa",
            1e4,
            "hot side pressure drop at m_nominal (used when hot_k is not given)",
            min=0.0,
        ),
        Param(
            "cold_dp_nominal",
            "delta_Pa",
            1e4,
            "cold side pressure drop at m_nominal (used when cold_k is not given)",
            min=0.0,
        ),
        Param(
            "phase_switches",
            "1",
            False,
            "locate crossings of the saturation lines per volume (condensable media; with IF97 "
            "each volume's phase is a discrete mode, see dnasim.components.channel)",
            kind="bool",
        ),
        Param("C_wall", "J/K", doc="wall heat capacity", min=0.0),
        Param(
            "flow",
            "1",
            "counter",
            "flow arrangement: counter-flow or parallel-flow",
            kind="string",
            choices=("counter", "parallel"),
        ),
        Param(
            "hot_kA_exponent",
            "1",
            0.0,
            "hot side: kA ~ m^e (0.8: turbulent convection; 0: constant)",
            min=0.0,
            max=2.0,
        ),
        Param(
            "cold_kA_exponent",
            "1",
            0.0,
            "cold side: kA ~ m^e (0.8: turbulent convection; 0: constant)",
            min=0.0,
            max=2.0,
        ),
        Param("hot_m_kA", "kg/s", None, "hot flow at which hot_kA holds (default m_nominal)"),
        Param("cold_m_kA", "kg/s", None, "cold flow at which cold_kA holds (default m_nominal)"),
        Param("n_sections", "1", 1, "number of sections", min=1, max=1000, kind="int"),
        Param("m_nominal", "kg/s", 1.0, "typical mass flow", min=0.0),
        Param(
            "dT_reg",
            "delta_K",
            1.0,
            "LMTD regularisation width (exact LMTD for differences >~ 10 dT_reg)",
            min=0.0,
        ),
        Param("hot_T0", "K", None, "initial hot fluid temperature (given start)", min=0.0),
        Param("cold_T0", "K", None, "initial cold fluid temperature (given start)", min=0.0),
        Param(
            "medium",
            "1",
            None,
            "fluid name on both sides (default: from the network)",
            kind="string",
        ),
        Param(
            "hot_medium", "1", None, "fluid name on the hot side (overrides medium)", kind="string"
        ),
        Param(
            "cold_medium",
            "1",
            None,
            "fluid name on the cold side (overrides medium)",
            kind="string",
        ),
    )
    FLUID_PORTS = (
        FluidPort("hot_in", "inlet", "hot_m[0]", "resistance", "hot fluid in"),
        FluidPort("hot_out", "outlet", "hot_m[n]", "storage", "hot fluid out (storage)"),
        FluidPort("cold_in", "inlet", "cold_m[0]", "resistance", "cold fluid in"),
        FluidPort("cold_out", "outlet", "cold_m[n]", "storage", "cold fluid out"),
    )

    def setup(self):
        P = self.params
        if P["C_wall"] <= 0 or P["hot_V"] <= 0 or P["cold_V"] <= 0:
            raise PlantError(f"component '{self.name}': hot_V, cold_V and C_wall must be > 0")
        n = self.n = P["n_sections"]
        self.parallel = P["flow"] == "parallel"
        #: the wall section next to cold section i
        self.cold_wall = list(range(n)) if self.parallel else [n - 1 - i for i in range(n)]
        self.channels = {}
        for side in ("hot", "cold"):
            wall = [f"T_w[{i}]" if side == "hot" else f"T_w[{self.cold_wall[i]}]" for i in range(n)]
            self.channels[side] = Channel(
                prefix=f"{side}_",
                inlet=f"{side}_in",
                outlet=f"{side}_out",
                n=n,
                V=P[f"{side}_V"],
                k=P[f"{side}_k"],
                dp_nominal=P[f"{side}_dp_nominal"],
                dz=0.0,
                kA=P[f"{side}_kA"],
                m_nominal=P["m_nominal"],
                m_reg=M_REG_REL * P["m_nominal"],
                dT_reg=P["dT_reg"],
                internal_energy="outlet",
                wall=wall,
                kA_exponent=P[f"{side}_kA_exponent"],
                m_kA=P[f"{side}_m_kA"],
            )

    def fluid_ports(self):
        n = self.n
        out = []
        for side, ch in self.channels.items():
            param = f"{side}_k" if self.params[f"{side}_k"] is not None else f"{side}_dp_nominal"
            out += [
                FluidPort(
                    f"{side}_in",
                    "inlet",
                    f"{side}_m[0]",
                    "storage" if ch.frictionless else "resistance",
                    h_out=ch.h_out_inlet(),
                    pressure_param=param,
                    m_eps=ch.m_eps,
                ),
                FluidPort(
                    f"{side}_out",
                    "outlet",
                    f"{side}_m[{n}]",
                    "storage",
                    h_out=ch.h_out_outlet(),
                    m_eps=ch.m_eps,
                ),
            ]
        return out

    def structure_problems(self):
        out = []
        for side, ch in self.channels.items():
            if self.n > 1 and ch.frictionless:
                param = (
                    f"{side}_k" if self.params[f"{side}_k"] is not None else f"{side}_dp_nominal"
                )
                out.append(
                    f"component '{self.name}' (HeatExchanger): friction parameter '{param}' = 0 "
                    f"with n_sections = {self.n}: the {side} side's storage volumes are joined "
                    "with no flow resistance between them, so their pressures are set twice and "
                    f"the DAE has index 2. Give {param} > 0."
                )
        return out

    def medium_groups(self):
        """Two streams, two media: the hot ports and the cold ports."""
        P = self.params
        return [
            (
                side,
                f"{side}_medium" if P[f"{side}_medium"] else "medium",
                [f"{side}_in", f"{side}_out"],
            )
            for side in ("hot", "cold")
        ]

    def side_medium(self, side):
        """The medium object of one stream ("hot" or "cold")."""
        return self.port_media.get(f"{side}_in")

    def _phase_sides(self):
        """(channel, medium) of the sides with phase switches; with IF97 (forced phase
        branches) each volume's phase is a discrete mode (``dnasim.components.channel``)."""
        if not self.params["phase_switches"]:
            return []
        out = []
        for side in ("hot", "cold"):
            medium = self.side_medium(side)
            if medium is not None and is_condensable(medium):
                ch = self.channels[side]
                if has_phase_branches(medium) and not ch.phase_modes:
                    ch.use_phase_modes()
                out.append((ch, medium))
        return out

    def switches(self):
        return [sw for ch, medium in self._phase_sides() for sw in ch.switches(medium)]

    def init_discrete_state(self, t0, x, xp) -> bool:
        changed = False
        for ch, medium in self._phase_sides():
            changed = ch.init_phase_modes(medium, x) or changed
        return changed

    def variables(self):
        out = []
        for side, ch in self.channels.items():
            M_nom = self.params[f"{side}_V"] / self.n * 1e-3
            out += ch.variables(
                M_nom,
                M_nom * 1e3,
                1e5,
                1e5,
                max(self.params[f"{side}_kA"] / self.n * DT_Q_NOMINAL, 1.0),
            )
        return out + [Variable("T_w", "K", 300.0, self.n, "wall temperature of section i")]

    def equations(self):
        n, C_i = self.n, self.params["C_wall"] / self.n
        eqs = self.channels["hot"].equations() + self.channels["cold"].equations()
        cold_wall = self.cold_wall  # the wall mapping is its own inverse
        eqs.append(
            Equation(
                "wall",
                size=n,
                y=lambda i: (f"hot_Q[{i}]", f"cold_Q[{cold_wall[i]}]"),
                yp=lambda i: (f"T_w[{i}]",),
                doc=f"{C_i:g} dT_w[i]/dt = hot_Q[i] + cold_Q[j(i)]"
                " (j(i) = n-1-i counter-flow, i parallel-flow)",
                unit="W",
                residual=lambda t, x, xp: C_i * xp["T_w"] - (x["hot_Q"] + x["cold_Q"][cold_wall]),
            )
        )
        return eqs

    def prepare(self, t, x, xp):
        """One property call per side, then both channels' blocks."""
        T_w = x["T_w"]
        hot, cold = self.channels["hot"], self.channels["cold"]
        work = hot.blocks(x, xp, hot.evaluate(self.side_medium("hot"), x), T_w)
        work.update(
            cold.blocks(x, xp, cold.evaluate(self.side_medium("cold"), x), T_w[self.cold_wall])
        )
        return work

    def outputs(self):
        return [
            Output("hot_T_out", "K", "hot outlet temperature"),
            Output("cold_T_out", "K", "cold outlet temperature"),
            Output("Q_total", "W", "heat from hot fluid to wall"),
        ]

    def output_values(self, t, x, xp):
        _, _, Th, _, _ = self.channels["hot"].evaluate(self.side_medium("hot"), x)
        _, _, Tc, _, _ = self.channels["cold"].evaluate(self.side_medium("cold"), x)
        return [Th[-2], Tc[-2], float(np.sum(x["hot_Q"]))]

    def design_values(self, t0, x):
        """The cold side's flow and the heat into it, -sum(cold_Q) [W] (at rest the heat
        the hot side gives); heat from outside the working fluid when the two sides
        carry different fluids (flue gas to water: an economiser, a superheater)."""
        duty = -float(np.sum(x["cold_Q"]))
        out = {"m": float(x["cold_m"][0]), "duty": duty}
        hot, cold = self.side_medium("hot"), self.side_medium("cold")
        if hot is not None and cold is not None and hot.label != cold.label and duty > 0.0:
            out["heat_in"] = duty
        return out

    def initial_guess(self, t0, x):
        n = self.n
        frac = (np.arange(n) + 1.0) / n
        T = {}
        for side, ch in self.channels.items():
            p_in, h_in = x[f"{side}_in.p"], x[f"{side}_in.h"]
            p = p_in + (x[f"{side}_out.p"] - p_in) * frac
            T0 = self.params[f"{side}_T0"]
            if T0 is not None:
                h = np.array([self.side_medium(side).h_pT(pi, T0) for pi in p])
            else:
                h = np.full(n, h_in)
            T[side] = ch.guess(x, self.side_medium(side), p, h, self.params["m_nominal"])
        x["T_w"] = 0.5 * (T["hot"] + T["cold"][self.cold_wall])
