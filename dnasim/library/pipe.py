"""Pipe: the seed's lumped pipe model (eqs. 10.12), optionally split into
``n_volumes`` control volumes in series."""

from __future__ import annotations

import math

import numpy as np

from dnasim.core.errors import PlantError, ResidualDomainError
from dnasim.library.submodels.channel import Channel, ChannelRows
from dnasim.library.submodels.tube_geometry import tube_params, tubes_from_params
from dnasim.library.submodels.tube_laws import ChannelLaws, TubeConvection, TubeFriction
from dnasim.model.component import Component, Equation, FluidPort, Output, Param, Variable
from dnasim.model.physics import (
    DT_Q_NOMINAL,
    M_REG_REL,
    has_phase_branches,
    is_condensable,
    upwind_weight,
)


class Pipe(Component):
    """Lumped pipe with wall heat capacity (seed eqs. 10.12), n_volumes in series.

    Each volume i (i = 0..n-1; V_i = V/n, kA_i = kA/n, k_i = k/n, C_i = C_wall/n) has
    its own state p_v[i], h_v[i]; energy is carried upwind of the actual flow, in
    either direction (``dnasim.library.submodels.channel`` for the full equations):

      mass[i]             dM[i]/dt = m[i] - m[i+1]                       (10.12a)
      energy[i]           dU[i]/dt = E[i] - E[i+1] - Q[i],  E[j] = w(m[j]) h_left - w(-m[j]) h_right
      wall[i]             C_i dT_w[i]/dt = Q[i]                         (with energy: 10.12b,
                                                                         U_s = C_wall T_w)
                          or T_w[i] = T_wall(t) when T_wall is given (fixed wall)
                          or T_w[i] = T_i when C_wall = kA = 0 (adiabatic, no wall)
      density[i]          M[i] = V_i rho(p_v[i], h_v[i])                 (10.12d)
      internal_energy[i]  U[i] = M[i] u_i              ("outlet", mixed volume: default)
                          U[i] = M[i] (u_a + u_i)/2    (10.12c, "mean": u_a = inflow state;
                          the seed's option, not physical: after a step of the inflow the
                          outflow first jumps the other way, and a gas may leave colder
                          than anything in the plant)
      heat[i]             Q[i] = kA_i LMTD(T_a - T_w[i], T_i - T_w[i])  (10.12e, "lmtd")
                          (or kA_i (T_i - T_w[i]) "outlet", kA_i ((T_a + T_i)/2 - T_w[i]) "mean")
      momentum[i]         p_left - p_v[i] = k_i m[i] sqrt(m[i]^2 + m_reg^2)/rho_f + rho_f g dz/n
      outlet_pressure     p_outlet = p_v[n-1]
      heat_passed         dQ_passed/dt = sum_i Q[i]     (fixed wall only: heat to the wall [J])

    m[0] is the inlet flow, m[n] the outlet flow (positive inlet -> outlet; either
    sign allowed). Unknowns and equations: 7n + 1 (+1 with a fixed wall). The port
    energy flows are E[0] (into the pipe at the inlet) and E[n] (out at the outlet).
    Friction sits at the inlet face of each volume, so a pipe's outlet is a storage
    volume: connect it to a pressure boundary or another storage volume only
    through a flow resistance (e.g. a Valve), otherwise the DAE has index 2. With
    k = 0 the inlet is a storage volume too (``dnasim check`` names 'k').

    Balances over a run: d(M_total)/dt = m[0] - m[n];
    d(U_total + E_wall)/dt = E[0] - E[n] - (sum Q with a fixed wall: Q_passed).

    Wall model (``dnasim.library.submodels.walls``), when wall_layers > 0 or an outer
    boundary is given: the wall of each volume is 1 (lumped) or wall_layers + 1
    radial nodes (r_in, r_out, length, wall_conductivity; shell conductances
    2 pi lambda l/ln(r_k+1/r_k)), with C_wall spread over the nodes, and on the
    outside convection kA_outer (T_outer(t) - T), a heat flux Q_outer(t) [W], or a
    fixed outer surface temperature T_outer(t) (no kA_outer). Q_passed [J] then
    integrates the heat leaving through the outer surface, E_wall sums C_k T_k.

    Given start (start="given"): the fluid starts at pressure p0 (default: the
    node guesses) and temperature T0, the wall at T_wall0 (default T0).

    From geometry (D given; ``dnasim.library.submodels.tube_geometry``, ``tube_laws``): n_tubes
    parallel tubes of inner diameter D and length ``length``, V = n_tubes pi D^2/4
    length (V is then not given); with wall_thickness and wall_material the wall's mass
    m_w, its capacity m_w c(T_w) (the wall equation m_w/n c(T_w) dT_w/dt = Q[i], E_wall
    = m_w/n sum e(T_w)) and its conduction lambda(T_w) (C_wall is then not given; a
    layered wall takes r_in = D/2, r_out = D/2 + wall_thickness and the metal's
    lambda(T)). friction = "colebrook" (default with D) or "haaland": the momentum
    balance's friction is Darcy-Weisbach per face with the two-phase multiplier
    two_phase_friction ("friedel", default, or "homogeneous"), and the static head
    uses the face's mixture density (void_fraction "homogeneous", the mass balance's,
    or "zivi"); convection = "gnielinski" (default with D and a wall) or
    "dittus_boelter": Q[i] = UA_i LMTD(...) with UA_i from the inside coefficient
    (single phase; Chen's flow boiling with the dry-out quality x_dryout, Shah's
    condensation) and the inner half of the wall. "lumped" keeps k or kA; giving k
    or kA with a correlation is an error. dz, the height of the outlet above the
    inlet, gives the static head in both forms.
    """

    PARAMS = (
        Param(
            "V", "m3", None, "fluid volume: required, unless D is given (then computed)", min=0.0
        ),
        Param("kA", "W/K", 0.0, "heat transfer coefficient times area, fluid to wall", min=0.0),
        Param("k", "1/m4", 0.0, "friction coefficient: dp = k m|m|/rho", min=0.0),
        Param("dz", "m", 0.0, "height of outlet above inlet"),
        *tube_params("pipe (tube) length: the geometry's, and a layered wall's"),
        Param(
            "friction",
            "1",
            None,
            "friction law: 'lumped' (k) or Darcy-Weisbach from geometry 'colebrook' / "
            "'haaland' (default: colebrook when D is given, else lumped)",
            kind="string",
            choices=("lumped", "colebrook", "haaland"),
        ),
        Param(
            "two_phase_friction",
            "1",
            "friedel",
            "two-phase friction from geometry: friedel (Friedel 1979) or homogeneous",
            kind="string",
            choices=("friedel", "homogeneous"),
        ),
        Param(
            "void_fraction",
            "1",
            "homogeneous",
            "static head's two-phase density from geometry: homogeneous (the mass balance's) "
            "or zivi (Zivi 1964)",
            kind="string",
            choices=("homogeneous", "zivi"),
        ),
        Param(
            "convection",
            "1",
            None,
            "fluid-to-wall heat transfer: 'lumped' (kA) or from geometry 'gnielinski' (VDI "
            "G1) / 'dittus_boelter', with Chen boiling and Shah condensation (default: "
            "gnielinski when D is given and there is a wall, else lumped)",
            kind="string",
            choices=("lumped", "gnielinski", "dittus_boelter"),
        ),
        Param(
            "x_dryout",
            "1",
            0.9,
            "critical (dry-out) quality of Chen's flow boiling (geometry)",
            min=0.0,
            max=1.0,
        ),
        Param(
            "C_wall", "J/K", 0.0, "heat capacity of the wall (mass times specific heat)", min=0.0
        ),
        Param(
            "T_wall",
            "K",
            None,
            "prescribed wall temperature (no wall storage)",
            min=0.0,
            time_function=True,
        ),
        Param(
            "n_volumes", "1", 1, "number of control volumes in series", min=1, max=5000, kind="int"
        ),
        Param(
            "internal_energy",
            "1",
            None,
            "U = M u_out ('outlet': mixed volume, default) or U = M (u_in+u_out)/2 ('mean', "
            "seed eq. 10.12c; jumps opposite to an inlet step, and a gas may leave colder than "
            "anything in the plant: not physical, kept as the seed's option; dnasim check "
            "notes it)",
            kind="string",
            choices=("mean", "outlet"),
        ),
        Param(
            "heat_transfer",
            "1",
            "lmtd",
            "temperature difference: log-mean (seed), outlet (upwind) or mean",
            kind="string",
            choices=("lmtd", "outlet", "mean"),
        ),
        Param("m_nominal", "kg/s", 1.0, "typical mass flow (scales and tolerances)", min=0.0),
        Param(
            "m_reg", "kg/s", None, "friction regularisation flow (default 1e-2 m_nominal)", min=0.0
        ),
        Param(
            "dT_reg",
            "delta_K",
            1.0,
            "LMTD regularisation width (exact LMTD for differences >~ 10 dT_reg)",
            min=0.0,
        ),
        Param(
            "phase_switches",
            "1",
            True,
            "locate crossings of the saturation lines per volume (condensable media; with IF97 "
            "each volume's phase is a discrete mode, see dnasim.library.submodels.channel)",
            kind="bool",
        ),
        Param(
            "wall_layers",
            "1",
            0,
            "radial conduction layers of the wall (0: lumped; see dnasim.library.submodels.walls)",
            min=0,
            max=100,
            kind="int",
        ),
        Param("r_in", "m", None, "inner wall radius (layered wall)", min=0.0),
        Param("r_out", "m", None, "outer wall radius (layered wall)", min=0.0),
        Param("wall_conductivity", "W/(m.K)", None, "wall conductivity (layered wall)", min=0.0),
        Param(
            "T_outer",
            "K",
            None,
            "outer boundary: with kA_outer the temperature convected to, without it the "
            "temperature of the wall's outer surface",
            min=0.0,
            time_function=True,
        ),
        Param("kA_outer", "W/K", None, "outer heat transfer coefficient times area", min=0.0),
        Param(
            "Q_outer",
            "W",
            None,
            "heat flux into the wall through its outer surface (total over the pipe)",
            time_function=True,
        ),
        Param("p0", "Pa", None, "initial fluid pressure (given start)", min=0.0),
        Param("T0", "K", None, "initial fluid temperature (given start)", min=0.0),
        Param("T_wall0", "K", None, "initial wall temperature (given start), default T0", min=0.0),
        Param(
            "medium",
            "1",
            None,
            "fluid name, e.g. 'Air', 'Water' (default: from the network)",
            kind="string",
        ),
    )
    FLUID_PORTS = (
        FluidPort("inlet", "inlet", "m[0]", "resistance", "fluid in (friction at this face)"),
        FluidPort("outlet", "outlet", "m[n]", "storage", "fluid out; pressure = last volume's"),
    )

    def setup(self):
        P = self.params
        n = P["n_volumes"]
        self.tubes = tubes_from_params(self.name, P)
        self._check_geometry()
        self.V = self.tubes.V if self.tubes is not None else P["V"]
        if self.V <= 0:
            raise PlantError(f"component '{self.name}': parameter 'V' must be > 0 m3")
        #: the wall's metal (geometry with wall_thickness and wall_material), or None
        walled = self.tubes is not None and self.tubes.has_wall
        self.wall_metal = self.tubes.metal if walled else None
        self.wall_model = None
        if P["wall_layers"] or any(P[k] is not None for k in ("T_outer", "kA_outer", "Q_outer")):
            if P["T_wall"] is not None:
                raise PlantError(
                    f"component '{self.name}': T_wall (a prescribed wall) excludes the wall "
                    "model (wall_layers, T_outer, kA_outer, Q_outer); for a fixed outer "
                    "surface temperature give T_outer"
                )
            from dnasim.library.submodels.walls import WallModel

            t = self.tubes
            metal = self.wall_metal
            self.wall_model = WallModel(
                owner=self.name,
                n=n,
                C_wall=t.wall_mass if metal is not None else P["C_wall"],
                layers=P["wall_layers"],
                r_in=t.D / 2 if metal is not None else P["r_in"],
                r_out=t.D_out / 2 if metal is not None else P["r_out"],
                # the shells of all tubes in parallel: their length is n_tubes length
                length=t.n_tubes * t.length if metal is not None else P["length"],
                conductivity=P["wall_conductivity"],
                T_outer=P["T_outer"],
                kA_outer=P["kA_outer"],
                Q_outer=P["Q_outer"],
                param_at=self.param_at,
                metal=metal,
            )
        if (
            P["C_wall"] == 0
            and P["T_wall"] is None
            and P["kA"] > 0
            and self.wall_model is None
            and self.wall_metal is None
        ):
            raise PlantError(
                f"component '{self.name}': with kA > 0 give either C_wall > 0 (wall storage) or "
                "T_wall (fixed wall)"
            )
        self.n = n
        # "mean" extrapolates each volume's state from its inflow (u_i = 2U/M - u_a):
        # an inlet step moves the outlet the opposite way, chained volumes zig-zag.
        self.internal_energy = P["internal_energy"] or "outlet"
        self.fixed_wall = P["T_wall"] is not None
        # kA = 0 and no wall capacity: adiabatic pipe, the wall variable just follows the fluid
        self.no_wall = (
            not self.fixed_wall
            and P["C_wall"] == 0
            and self.wall_model is None
            and self.wall_metal is None
        )
        m_reg = P["m_reg"] if P["m_reg"] is not None else M_REG_REL * max(P["m_nominal"], 1e-12)
        laws = self._laws(n, m_reg)
        self.channel = Channel(
            prefix="",
            inlet="inlet",
            outlet="outlet",
            n=n,
            V=self.V,
            k=P["k"] if self.friction == "lumped" else None,
            dz=P["dz"],
            kA=P["kA"],
            m_nominal=P["m_nominal"],
            m_reg=m_reg,
            dT_reg=P["dT_reg"],
            internal_energy=self.internal_energy,
            wall=[f"T_w[{i}]" for i in range(n)],
            heat_transfer=P["heat_transfer"],
            laws=laws,
        )

    def _check_geometry(self):
        """The combinations of the lumped and the geometry parameters (class doc): a
        quantity the geometry gives may not be given too, a correlation needs D."""
        P, name, geo = self.params, self.name, self.tubes is not None
        if geo:
            for key in ("V", "r_in", "r_out"):
                if P[key] is not None:
                    raise PlantError(
                        f"component '{name}': '{key}' follows from the geometry (D, length, "
                        "n_tubes, wall_thickness): leave it out, or leave out D for the lumped "
                        "pipe"
                    )
            if self.tubes.has_wall:
                for key, default in (("C_wall", 0.0), ("wall_conductivity", None)):
                    if P[key] != default:
                        raise PlantError(
                            f"component '{name}': '{key}' follows from wall_thickness and "
                            f"wall_material ({self.tubes.metal.name}): leave it out"
                        )
        elif P["V"] is None:
            raise PlantError(
                f"component '{name}' (Pipe): parameter 'V' [m3] is required (fluid volume), "
                "unless the pipe is given by geometry: the tubes' inner diameter D and length"
            )
        self.friction = P["friction"] or ("colebrook" if geo else "lumped")
        has_wall = (
            P["T_wall"] is not None
            or P["C_wall"] > 0
            or (geo and self.tubes.has_wall)
            or P["wall_layers"] > 0
            or any(P[k] is not None for k in ("T_outer", "kA_outer", "Q_outer"))
        )
        self.convection = P["convection"] or ("gnielinski" if geo and has_wall else "lumped")
        for what, law, lumped, unit in (
            ("friction", self.friction, "k", "1/m4"),
            ("convection", self.convection, "kA", "W/K"),
        ):
            if law == "lumped":
                continue
            if not geo:
                raise PlantError(
                    f"component '{name}': {what} = '{law}' is a correlation from geometry: give "
                    "the tubes' inner diameter D and length (or the lumped '{lumped}')"
                )
            if P[lumped] != 0:
                raise PlantError(
                    f"component '{name}': '{lumped}' = {P[lumped]:g} {unit} (lumped) and "
                    f"{what} = '{law}' (from geometry) are two models of one thing: give "
                    f"one (leave out '{lumped}', or set {what} = 'lumped')"
                )
        if self.convection != "lumped" and not has_wall:
            raise PlantError(
                f"component '{name}': convection = '{self.convection}' needs a wall to transfer "
                "heat to: wall_thickness and wall_material, C_wall, T_wall or an outer boundary"
            )

    def _laws(self, n, m_reg):
        """The ``tube_laws.ChannelLaws`` of a pipe from geometry, or None."""
        P = self.params
        if self.friction == "lumped" and self.convection == "lumped":
            return None
        friction = heat = None
        if self.friction != "lumped":
            friction = TubeFriction(
                self.tubes, n, self.friction, P["two_phase_friction"], m_reg, P["void_fraction"]
            )
        if self.convection != "lumped":
            # a layered wall's node 0 is the inner surface; a lumped wall's the mean radius
            layered = self.wall_model is not None and self.wall_model.layers > 0
            heat = TubeConvection(
                self.tubes, n, self.convection, P["x_dryout"], m_reg, wall_resistance=not layered
            )
        return ChannelLaws(n, friction, heat)

    def fluid_ports(self):
        ch = self.channel
        inlet_role = "storage" if ch.frictionless else "resistance"
        return [
            FluidPort(
                "inlet",
                "inlet",
                "m[0]",
                inlet_role,
                "fluid in",
                h_out=ch.h_out_inlet(),
                pressure_param="k" if self.friction == "lumped" else "D",
                m_eps=ch.m_eps,
            ),
            FluidPort(
                "outlet",
                "outlet",
                f"m[{self.n}]",
                "storage",
                "fluid out",
                h_out=ch.h_out_outlet(),
                m_eps=ch.m_eps,
            ),
        ]

    def structure_problems(self):
        if self.n > 1 and self.channel.frictionless:
            return [
                f"component '{self.name}' (Pipe): friction parameter 'k' = 0 with n_volumes = "
                f"{self.n}: its {self.n} storage volumes are joined with no flow resistance "
                "between them, so their pressures are set twice and the DAE has index 2. Give "
                "k > 0."
            ]
        return []

    def _phase_modes_on(self) -> bool:
        """Phase switches on a condensable medium; with IF97 (forced phase branches)
        as discrete modes per volume (``dnasim.library.submodels.channel``, "Phase modes")."""
        if not (self.params["phase_switches"] and is_condensable(self.medium)):
            return False
        if has_phase_branches(self.medium) and not self.channel.phase_modes:
            self.channel.use_phase_modes()
        return True

    def switches(self):
        if self._phase_modes_on():
            return self.channel.switches(self.medium)
        return []

    def init_discrete_state(self, t0, x, xp) -> bool:
        if self._phase_modes_on():
            return self.channel.init_phase_modes(self.medium, x)
        return False

    def variables(self):
        P = self.params
        # M and U scales are raised to |initial value| by the assembly
        M_nom = self.V / self.n * 1e-3
        U_nom = M_nom * 1e3
        kA = P["kA"]
        if self.convection != "lumped":  # a scale only: 1000 W/(m2 K) on the inner surface
            kA = 1000.0 * self.tubes.A_inner
        Q_nom = max(kA / self.n * DT_Q_NOMINAL, 1.0)
        out = self.channel.variables(M_nom, U_nom, 1e5, 1e5, Q_nom) + [
            Variable("T_w", "K", 300.0, self.n, "wall temperature of volume i"),
        ]
        if self.wall_model is not None:
            out += self.wall_model.variables(300.0, Q_nom)
        if self.fixed_wall:
            out.append(
                Variable(
                    "Q_passed",
                    "J",
                    Q_nom,
                    doc="heat from the fluid to the fixed wall, integral of sum Q dt",
                    accumulator=True,
                )
            )
        return out

    def equations(self):
        n, C_i = self.n, self.params["C_wall"] / self.n
        eqs = self.channel.equations()
        if self.wall_model is not None:  # walls.py
            return eqs + self.wall_model.equations()
        if self.fixed_wall:
            eqs.append(
                Equation(
                    "wall",
                    size=n,
                    y=lambda i: (f"T_w[{i}]",),
                    doc="T_w[i] = T_wall(t)",
                    unit="K",
                    residual=lambda t, x, xp: x["T_w"] - self.param_at("T_wall", t),
                )
            )
            eqs.append(
                Equation(
                    "heat_passed",
                    y=tuple(f"Q[{i}]" for i in range(n)),
                    yp=("Q_passed",),
                    doc="dQ_passed/dt = sum Q",
                    unit="W",
                    residual=lambda t, x, xp: xp["Q_passed"] - np.sum(x["Q"]),
                )
            )
        elif self.wall_metal is not None:
            m_i, metal = self.tubes.wall_mass / n, self.wall_metal
            eqs.append(
                Equation(
                    "wall",
                    size=n,
                    y=lambda i: (f"Q[{i}]", f"T_w[{i}]"),
                    yp=lambda i: (f"T_w[{i}]",),
                    doc=f"{m_i:g} c(T_w[i]) dT_w[i]/dt = Q[i] ({metal.name})",
                    unit="W",
                    residual=lambda t, x, xp: (
                        m_i * metal.heat_capacity(x["T_w"]) * xp["T_w"] - x["Q"]
                    ),
                )
            )
        elif self.no_wall:
            eqs.append(
                Equation(
                    "wall",
                    size=n,
                    y=lambda i: (f"T_w[{i}]",) + self.channel.state_names(i + 1),
                    doc="T_w[i] = T_i (adiabatic)",
                    unit="K",
                    residual=lambda t, x, xp: x["T_w"] - x.work["T"][1:-1],
                )
            )
        else:
            eqs.append(
                Equation(
                    "wall",
                    size=n,
                    y=lambda i: (f"Q[{i}]",),
                    yp=lambda i: (f"T_w[{i}]",),
                    doc=f"{C_i:g} dT_w[i]/dt = Q[i]",
                    unit="W",
                    residual=lambda t, x, xp: C_i * xp["T_w"] - x["Q"],
                )
            )
        return eqs

    def batch_key(self):
        """Pipes with equal keys are evaluated together, as one vectorised block over the
        plant-wide vectors (``PipeBatch``, made by ``dnasim.compilation.system``): alike channels
        (``Channel.batch_key``) and no layered wall model; None: alone (also for a
        subclass, which may change the equations)."""
        if type(self) is not Pipe or self.wall_model is not None or self.wall_metal is not None:
            return None
        key = self.channel.batch_key()
        return None if key is None else ("Pipe", *key)

    @staticmethod
    def batch(blocks):
        """The ``PipeBatch`` of the System blocks of pipes with one ``batch_key``."""
        return PipeBatch(blocks)

    def prepare(self, t, x, xp):
        """One property call for the n + 2 states, then every channel block."""
        props = self.channel.evaluate(self.medium, x)
        work = self.channel.blocks(x, xp, props, x["T_w"], self.medium)
        work["T"] = props[2]
        return work

    def outputs(self):
        return [
            Output("T_in", "K", "inlet temperature"),
            Output("T_out", "K", "outlet temperature"),
            Output("M_total", "kg", "fluid mass in the pipe"),
            Output("U_total", "J", "fluid internal energy in the pipe"),
            Output("E_wall", "J", "wall energy C_wall T_w (reference 0 K)"),
            Output("Q_total", "W", "heat flow from fluid to wall"),
            Output("E_in", "W", "energy flow into the pipe at the inlet"),
            Output("E_out", "W", "energy flow out of the pipe at the outlet"),
        ] + [Output(f"T[{i}]", "K", f"fluid temperature of volume {i}") for i in range(self.n)]

    def output_values(self, t, x, xp):
        _, h, T, _, _ = self.channel.evaluate(self.medium, x)
        E = self.channel.face_energy(x["m"], h)
        C_i = self.params["C_wall"] / self.n
        return [
            T[0],
            T[-2],
            float(np.sum(x["M"])),
            float(np.sum(x["U"])),
            self.wall_energy(x, C_i),
            float(np.sum(x["Q"])),
            float(E[0]),
            float(E[-1]),
            *T[1:-1],
        ]

    def design_values(self, t0, x):
        """Flow at the inlet, heat into the fluid -sum(Q) [W] (Q: fluid to wall); heat
        from outside the plant when the wall is prescribed or heated from outside."""
        duty = -float(np.sum(x["Q"]))
        out = {"m": float(x["m"][0]), "duty": duty}
        outside = self.fixed_wall or self.params.get("Q_outer") is not None
        outside = outside or self.params.get("T_outer") is not None
        if outside and duty > 0.0:
            out["heat_in"] = duty
        return out

    def wall_energy(self, x, C_i) -> float:
        """E_wall [J]: the wall model's, m_w/n sum e(T_w) of a metal wall, else C_i sum T_w."""
        if self.wall_model is not None:
            return self.wall_model.energy(x)
        if self.wall_metal is not None:
            m_i = self.tubes.wall_mass / self.n
            return float(m_i * np.sum(self.wall_metal.enthalpy(x["T_w"])))
        return float(C_i * np.sum(x["T_w"]))

    def guess_nodes(self, t0):
        P = self.params
        if P["T0"] is None:
            return {}
        p = P["p0"]
        if p is None:
            return {"outlet": (None, None)}
        return {"outlet": (p, self.medium.h_pT(p, P["T0"]))}

    def initial_guess(self, t0, x):
        P = self.params
        n = self.n
        p_in, h_in = x["inlet.p"], x["inlet.h"]
        p_out = P["p0"] if P["p0"] is not None else x["outlet.p"]
        frac = (np.arange(n) + 1.0) / n
        p = p_in + (p_out - p_in) * frac
        if P["T0"] is not None:
            h = np.array([self.medium.h_pT(pi, P["T0"]) for pi in p])
        else:
            h = h_in + (x["outlet.h"] - h_in) * frac
        self._fill_guess(t0, x, p, h)

    def steady_guess(self, t0, x):
        """The steady start's guess (``Component.steady_guess``) of a pipe without T0 and
        without a layered wall model: at the flow m_nominal, the enthalpies marched from
        the inlet through a fixed wall's heat (``heated_guess``), or the inlet enthalpy in
        every volume when no heat flows at rest (a storage wall, C dT_w/dt = Q = 0, or
        no wall)."""
        P = self.params
        if P["T0"] is not None or self.wall_model is not None:
            return
        p = np.array(x[self.channel.pv], dtype=float)
        h = np.full(self.n, x["inlet.h"])
        if self.fixed_wall and P["kA"] > 0:
            h = self.heated_guess(p, x["inlet.h"], self.param_at("T_wall", t0), P["m_nominal"])
            if h is None:
                return
        before = x.data.copy()
        try:
            self._fill_guess(t0, x, p, h)
        except ResidualDomainError:  # a state the medium's array call refuses: keep the guess
            x.data[:] = before
            return
        if self.fixed_wall:  # Q[i] = -m (h_i - h_a): the heat of the march [W]
            x["Q"] = -P["m_nominal"] * np.diff(np.concatenate(([x["inlet.h"]], h)))

    def _fill_guess(self, t0, x, p, h):
        """The guesses of every variable from the volumes' p [Pa] and h [J/kg]."""
        P = self.params
        n = self.n
        T = self.channel.guess(x, self.medium, p, h, P["m_nominal"])
        if self.wall_model is not None:
            T_w0 = np.full(n, P["T_wall0"]) if P["T_wall0"] is not None else T
            self.wall_model.guess(t0, x, T_w0)
        elif self.fixed_wall:
            x["T_w"] = self.param_at("T_wall", t0)
            x["Q_passed"] = 0.0
        elif P["T_wall0"] is not None:
            x["T_w"] = P["T_wall0"]
        else:
            x["T_w"] = T

    def heated_guess(self, p, h_in, T_wall, m):
        """Steady enthalpies h_i [J/kg] of the volumes of a pipe heated by a fixed wall at
        T_wall [K], marched from the inlet state (p[0], h_in) volume by volume at the
        flow m [kg/s] (the steady start's guess, ``initial_guess``); None when a state is
        out of the medium's range. Per volume, with the inflow state a (T_a, c_p,a) and
        NTU_i = kA_i / (m c_p,a), the steady heat balance m (h_i - h_a) = -Q_i with
        Q_i = kA_i LMTD(T_a - T_wall, T_i - T_wall) has, for constant c_p, the solution
        T_i - T_wall = (T_a - T_wall) exp(-NTU_i), i.e.

            h_i = h_a + (kA_i / m) (T_wall - T_a) (1 - exp(-NTU_i)) / NTU_i

        which never passes T_wall, and is the explicit step kA_i (T_wall - T_a) / m for
        NTU_i -> 0 (c_p = inf in the two-phase dome)."""
        kA_i = self.params["kA"] / self.n
        h = np.empty(len(p))
        h_a = float(h_in)
        p_a = np.concatenate(([p[0]], p[:-1]))  # the inflow's pressure: the volume upstream
        try:
            for i in range(len(p)):
                s = self.medium.state(float(p_a[i]), h_a)
                ntu = kA_i / (m * s.cp) if np.isfinite(s.cp) and s.cp > 0 else 0.0
                factor = -math.expm1(-ntu) / ntu if ntu > 0 else 1.0
                h_a = h_a + kA_i / m * (T_wall - s.T) * factor
                h[i] = h_a
        except ResidualDomainError:
            return None
        return h if np.all(np.isfinite(h)) else None


class PipeBatch:
    """The residual rows of several pipes with one ``Pipe.batch_key``, evaluated as one:
    the channel blocks by ``ChannelRows`` over the pipes laid end to end, the wall
    equations over all their volumes, gathered from and written into the plant-wide
    vectors through index arrays made once. Each pipe's states go to its own property
    call (``Channel.state_properties``: its memo and phase modes), so every row is the
    one ``Pipe.residual`` gives, to the bit (tests/test_channel_batch.py). The wall rows
    restate ``Pipe.equations``' one-line wall residuals (T_w - T_wall(t), T_w - T_i,
    C_i dT_w/dt - Q, dQ_passed/dt - sum Q) over the batch's volumes; that test holds
    them to the bit too.

    ``blocks``: the System's ``ComponentBlock`` of each pipe (component, local -> global
    indices ``gidx``, local names ``index``, rows ``eq_slice``, discrete ``modes``)."""

    def __init__(self, blocks):
        self.blocks = list(blocks)
        self.names = tuple(b.comp.name for b in self.blocks)
        pipes = [b.comp for b in self.blocks]
        self.channel_rows = ChannelRows([pipe.channel for pipe in pipes])

        def at(b, name):
            k = b.index[name]
            return b.gidx[k] if isinstance(k, slice) else b.gidx[[k]]

        def cat(parts):
            return np.concatenate(parts).astype(np.intp)

        p_at, h_at, self.segments, start = [], [], [], 0
        for b in self.blocks:
            pos_p, pos_h = b.comp.channel._state_positions(b.index)
            p_at.append(b.gidx[pos_p])
            h_at.append(b.gidx[pos_h])
            self.segments.append(slice(start, start + b.comp.n + 2))
            start += b.comp.n + 2
        self.p_at, self.h_at = cat(p_at), cat(h_at)
        self.m_at, self.M_at, self.U_at, self.Q_at, self.Tw_at = (
            cat([at(b, name) for b in self.blocks]) for name in ("m", "M", "U", "Q", "T_w")
        )
        # the rows of each equation, pipe after pipe (each pipe's rows from eq_slice)
        rows = {}
        for b in self.blocks:
            offset = b.eq_slice.start
            for eq in b.comp.equations():
                rows.setdefault(eq.name, []).append(offset + np.arange(eq.n_rows))
                offset += eq.n_rows
            if offset != b.eq_slice.stop:  # pragma: no cover - equations() changed
                raise ValueError(f"PipeBatch: the rows of '{b.comp.name}' do not add up")
        self.rows = [cat(rows[name]) for name in ChannelRows.NAMES]
        # the wall equations, by kind: fixed T_wall(t), adiabatic (no wall), storage
        volumes, v0 = [], 0
        for b in self.blocks:
            volumes.append(np.arange(v0, v0 + b.comp.n))
            v0 += b.comp.n
        kinds = {"fixed": [], "none": [], "storage": []}
        for k, b in enumerate(self.blocks):
            pipe = b.comp
            kind = "fixed" if pipe.fixed_wall else "none" if pipe.no_wall else "storage"
            kinds[kind].append(k)
        self.walls = []
        for kind, members in kinds.items():
            if not members:
                continue
            vol = cat([volumes[k] for k in members])
            wall_rows = cat([rows["wall"][k] for k in members])
            self.walls.append((kind, [self.blocks[k].comp for k in members], vol, wall_rows))
        self.n = {kind: [pipe.n for pipe in pipes] for kind, pipes, _, _ in self.walls}
        self.fixed = [
            (volumes[k], int(rows["heat_passed"][i][0]), int(at(self.blocks[k], "Q_passed")[0]))
            for i, k in enumerate(kinds["fixed"])
        ]
        self.C_i = np.concatenate(
            [np.full(b.comp.n, b.comp.params["C_wall"] / b.comp.n) for b in self.blocks]
        )
        self._outputs = None  # the index arrays of ``output_values``, made on first use

    def _output_layout(self):
        """Index arrays of ``output_values``: the end faces of each pipe, its pipes
        grouped by volume count (for the sums), and where each output comes from."""
        k = len(self.blocks)
        ends, left, eps = [], [], []
        for b, seg in zip(self.blocks, self.segments, strict=True):
            m_at = b.gidx[b.index["m"]]
            ends += [m_at[0], m_at[-1]]  # faces 0 and n
            left += [seg.start, seg.stop - 2]  # the state left of each: S_0 and S_n
            eps += [b.comp.channel.m_eps] * 2
        groups = {}  # volume count -> positions of its pipes
        for i, b in enumerate(self.blocks):
            groups.setdefault(b.comp.n, []).append(i)

        def rows_of(name, members):
            return np.array([self.blocks[i].gidx[self.blocks[i].index[name]] for i in members])

        sums = [
            (np.array(members), *(rows_of(name, members) for name in ("M", "U", "T_w", "Q")))
            for members in groups.values()
        ]
        # the pool of ``output_values``: T of every state (the segments), then per pipe
        # M_total, U_total, E_wall, Q_total, then E at the end faces (two per pipe)
        n_T = self.segments[-1].stop
        src = []
        for i, (b, seg) in enumerate(zip(self.blocks, self.segments, strict=True)):
            n = b.comp.n
            src += [seg.start, seg.start + n]  # T_in = T[0], T_out = T[-2]
            src += [n_T + j * k + i for j in range(4)]  # M_total, U_total, E_wall, Q_total
            src += [n_T + 4 * k + 2 * i, n_T + 4 * k + 2 * i + 1]  # E_in, E_out
            src += range(seg.start + 1, seg.start + n + 1)  # T[1:-1]
        C_i = np.array([b.comp.params["C_wall"] / b.comp.n for b in self.blocks])
        return (
            np.array(ends, dtype=np.intp),
            np.array(left, dtype=np.intp),
            np.array(eps),
            sums,
            C_i,
            np.array(src, dtype=np.intp),
        )

    def output_values(self, t, y, yp) -> np.ndarray:
        """Every pipe's ``Pipe.output_values``, pipe after pipe, as one array: the same
        property calls (each pipe's own, ``Channel.state_properties``), the port energy
        flows E[0], E[n] over the end faces of all pipes at once, and the sums over
        the pipes with one volume count as one 2-D sum (each row the pairwise sum
        ``np.sum`` makes of it), so every value is ``Pipe.output_values``' to the bit
        (tests/test_output_rows.py)."""
        if self._outputs is None:
            self._outputs = self._output_layout()
        ends, left, eps, groups, C_i, src = self._outputs
        p = y[self.p_at]
        h = y[self.h_at]
        T = np.concatenate(
            [
                b.comp.channel.state_properties(b.comp.medium, p[seg], h[seg], b.modes)[0]
                for b, seg in zip(self.blocks, self.segments, strict=True)
            ]
        )
        k = len(self.blocks)
        sums = np.empty((4, k))  # M_total, U_total, E_wall, Q_total
        for members, M_at, U_at, Tw_at, Q_at in groups:
            sums[0, members] = y[M_at].sum(axis=1)
            sums[1, members] = y[U_at].sum(axis=1)
            sums[2, members] = C_i[members] * y[Tw_at].sum(axis=1)
            sums[3, members] = y[Q_at].sum(axis=1)
        m = y[ends]
        E = upwind_weight(m, eps) * h[left] - upwind_weight(-m, eps) * h[left + 1]
        return np.concatenate((T, sums.ravel(), E))[src]

    def residual_into(self, t, y, yp, F) -> None:
        """F[rows of the pipes] = their residuals at (t, y, y') (global vectors)."""
        p = y[self.p_at]
        h = y[self.h_at]
        props = [
            b.comp.channel.state_properties(b.comp.medium, p[seg], h[seg], b.modes)
            for b, seg in zip(self.blocks, self.segments, strict=True)
        ]
        T, rho, u = (np.concatenate(v) for v in zip(*props, strict=True))
        Q, T_w = y[self.Q_at], y[self.Tw_at]
        M, U = self.M_at, self.U_at
        values = self.channel_rows.residuals(
            p, h, T, rho, u, y[self.m_at], y[M], y[U], Q, yp[M], yp[U], T_w
        )
        for rows, v in zip(self.rows, values, strict=True):
            F[rows] = v
        for kind, pipes, vol, rows in self.walls:
            if kind == "fixed":  # T_w[i] = T_wall(t)
                T_wall = np.repeat([pipe.param_at("T_wall", t) for pipe in pipes], self.n[kind])
                F[rows] = T_w[vol] - T_wall
            elif kind == "none":  # T_w[i] = T_i
                F[rows] = T_w[vol] - T[self.channel_rows.own][vol]
            else:  # C_i dT_w[i]/dt = Q[i]
                F[rows] = self.C_i[vol] * yp[self.Tw_at[vol]] - Q[vol]
        for vol, row, at_Q_passed in self.fixed:  # dQ_passed/dt = sum Q
            F[row] = yp[at_Q_passed] - np.sum(Q[vol[0] : vol[-1] + 1])
