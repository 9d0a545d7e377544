"""HeatExchanger: counter- or parallel-flow, lumped in n_sections, with wall heat
capacity and per-side flow-dependent heat transfer coefficients."""

from __future__ import annotations

import numpy as np

from dnasim.core.errors import PlantError
from dnasim.correlations.metals import metal, metal_names
from dnasim.library.submodels.channel import Channel
from dnasim.library.submodels.tube_geometry import TubeBank, tube_params, tubes_from_params
from dnasim.library.submodels.tube_laws import (
    BankConvection,
    ChannelLaws,
    TubeConvection,
    TubeFriction,
)
from dnasim.model.component import Component, Equation, FluidPort, Output, Param, Variable
from dnasim.model.physics import (
    DT_Q_NOMINAL,
    M_REG_REL,
    has_phase_branches,
    is_condensable,
)

#: the geometry parameters of the bank (outside of the tubes) side
BANK_KEYS = (
    "pitch_transverse",
    "pitch_longitudinal",
    "n_rows",
    "frontal_area",
    "fin_height",
    "fin_thickness",
    "fin_pitch",
    "fin_material",
)


class HeatExchanger(Component):
    """Heat exchanger: a hot and a cold channel of n_sections volumes each, sharing
    a wall. Hot section i faces cold section n-1-i (flow = "counter", default) or
    cold section i (flow = "parallel"). With gas on one side and water on the
    other (media per side: hot_medium, cold_medium, or from the nodes) it is an
    economiser, an evaporator or a superheater.

    Each channel is a series of volumes as in ``Pipe`` (prefix hot_ / cold_;
    ``dnasim.library.submodels.channel``): mass, energy, density, internal_energy, heat,
    momentum per volume and the outlet pressure tie, with energy upwind of the
    actual flow (either direction), U = M u per volume (mixed volumes), and
      heat      Q_side[i] = kA_side/n LMTD(T_a - T_w, T_i - T_w)   (fluid -> wall)
    and the wall, section i (C_i = C_wall/n):
      wall[i]   C_i dT_w[i]/dt = hot_Q[i] + cold_Q[j(i)],  j = n-1-i (counter), i (parallel)

    Per-side heat transfer coefficient with nominal-point scaling
    (``dnasim.library.submodels.walls.flow_scaled_kA``; alpha ~ m^0.8 for turbulent flow):
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

    From geometry (``dnasim.library.submodels.tube_geometry``, ``tube_laws``): D, length,
    n_tubes, wall_thickness, wall_material, roughness describe the tubes; the side
    tube_side ("cold", default, or "hot") flows inside them: its volume is the tubes',
    its friction Darcy-Weisbach (friction = "colebrook", default, or "haaland"; two
    phase by two_phase_friction) and its heat transfer the inside correlations
    (convection = "gnielinski", default, or "dittus_boelter"; Chen's boiling, Shah's
    condensation), through the inner half of the wall. The other side flows across
    the tubes as a bank when ``arrangement`` is given ("inline" or "staggered", with
    pitch_transverse, pitch_longitudinal, n_rows, optional frontal_area and annular
    fins fin_height, fin_thickness, fin_pitch, fin_material): its volume is the gas
    between the tubes, its heat transfer Zukauskas' with the fin efficiency (and gas
    radiation by WSGG with gas_radiation = true: a FlueGas mixture), through the outer
    half of the wall; its friction stays the lumped k or dp_nominal (no bank-friction
    correlation in the library). The wall's heat capacity is the tubes' and fins'
    m c(T_w) (C_wall is then not given): the wall equation
    sum_k m_k c_k(T_w[i])/n dT_w[i]/dt = hot_Q[i] + cold_Q[j(i)], and the output
    E_wall = sum_k m_k/n sum_i e_k(T_w[i]). A side's kA, V (and the tube side's k or
    dp_nominal) may not be given when the geometry gives them.
    """

    PARAMS = (
        Param("hot_V", "m3", None, "hot side volume (required unless from geometry)", min=0.0),
        Param("cold_V", "m3", None, "cold side volume (required unless from geometry)", min=0.0),
        Param(
            "hot_kA",
            "W/K",
            None,
            "hot side heat transfer coefficient times area (required unless from geometry)",
            min=0.0,
        ),
        Param(
            "cold_kA",
            "W/K",
            None,
            "cold side heat transfer coefficient times area (required unless from geometry)",
            min=0.0,
        ),
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
            "each volume's phase is a discrete mode, see dnasim.library.submodels.channel)",
            kind="bool",
        ),
        Param(
            "C_wall",
            "J/K",
            None,
            "wall heat capacity (required unless from wall_thickness and wall_material)",
            min=0.0,
        ),
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
        *tube_params(),
        Param(
            "tube_side",
            "1",
            "cold",
            "the side flowing inside the tubes (geometry)",
            kind="string",
            choices=("cold", "hot"),
        ),
        Param(
            "friction",
            "1",
            None,
            "tube side friction: 'lumped' (k or dp_nominal) or Darcy-Weisbach 'colebrook' / "
            "'haaland' (default: colebrook when D is given)",
            kind="string",
            choices=("lumped", "colebrook", "haaland"),
        ),
        Param(
            "two_phase_friction",
            "1",
            "friedel",
            "tube side two-phase friction (geometry): friedel or homogeneous",
            kind="string",
            choices=("friedel", "homogeneous"),
        ),
        Param(
            "convection",
            "1",
            None,
            "tube side heat transfer: 'lumped' (kA) or 'gnielinski' / 'dittus_boelter' with "
            "Chen boiling and Shah condensation (default: gnielinski when D is given)",
            kind="string",
            choices=("lumped", "gnielinski", "dittus_boelter"),
        ),
        Param(
            "x_dryout", "1", 0.9, "critical quality of Chen's boiling (geometry)", min=0.0, max=1.0
        ),  # fmt: skip
        Param(
            "arrangement",
            "1",
            None,
            "the other side flows across the tubes as a bank (Zukauskas): inline or staggered",
            kind="string",
            choices=("inline", "staggered"),
        ),
        Param("pitch_transverse", "m", None, "bank: transverse pitch S_T", min=0.0),
        Param("pitch_longitudinal", "m", None, "bank: longitudinal pitch S_L", min=0.0),
        Param("n_rows", "1", None, "bank: tube rows in the flow direction", min=1, kind="int"),
        Param(
            "frontal_area",
            "m2",
            None,
            "bank: frontal (duct) area of the approach flow (default n_tubes length S_T/n_rows)",
        ),
        Param("fin_height", "m", None, "bank: annular fin height (fins optional)", min=0.0),
        Param("fin_thickness", "m", None, "bank: fin thickness", min=0.0),
        Param("fin_pitch", "m", None, "bank: fin pitch, centre to centre", min=0.0),
        Param(
            "fin_material",
            "1",
            None,
            "bank: fin metal (default wall_material)",
            kind="string",
            choices=metal_names(),
        ),
        Param(
            "gas_radiation",
            "1",
            False,
            "bank: add the gas's radiation to the tubes (WSGG; a FlueGas mixture)",
            kind="bool",
        ),
        Param(
            "wall_emissivity",
            "1",
            0.8,
            "bank: emissivity of the tubes (radiation)",
            min=0.0,
            max=1.0,
        ),  # fmt: skip
        Param("beam_length", "m", None, "bank: mean beam length (default 3.6 V_gas/A_o)", min=0.0),
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
        n = self.n = P["n_sections"]
        self._geometry()
        if self.C_wall <= 0 or self.V["hot"] <= 0 or self.V["cold"] <= 0:
            raise PlantError(f"component '{self.name}': hot_V, cold_V and C_wall must be > 0")
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
                V=self.V[side],
                k=None if side == self.tube_side and self.friction != "lumped" else P[f"{side}_k"],
                dp_nominal=P[f"{side}_dp_nominal"],
                dz=0.0,
                kA=P[f"{side}_kA"] or 0.0,
                m_nominal=P["m_nominal"],
                m_reg=M_REG_REL * P["m_nominal"],
                dT_reg=P["dT_reg"],
                internal_energy="outlet",
                wall=wall,
                kA_exponent=P[f"{side}_kA_exponent"],
                m_kA=P[f"{side}_m_kA"],
                laws=self._laws(side, n, M_REG_REL * P["m_nominal"]),
            )

    # ------------------------------------------------------------- geometry
    def _geometry(self):
        """The tubes and the bank from the parameters, the volumes and the wall
        capacity each side and the wall get, and the combinations refused (class doc)."""
        P, name = self.params, self.name
        self.tubes = tubes_from_params(name, P)
        geo = self.tubes is not None
        self.tube_side = P["tube_side"]
        self.bank_side = "hot" if self.tube_side == "cold" else "cold"
        self.bank = None
        if P["arrangement"] is not None or any(P[k] is not None for k in BANK_KEYS):
            self.bank = self._bank()
        self.friction = P["friction"] or ("colebrook" if geo else "lumped")
        self.convection = P["convection"] or ("gnielinski" if geo else "lumped")
        for what, law in (("friction", self.friction), ("convection", self.convection)):
            if law != "lumped" and not geo:
                raise PlantError(
                    f"component '{name}': {what} = '{law}' is a correlation from geometry: "
                    "give the tubes (D, length, n_tubes, ...)"
                )
        tube, bank = self.tube_side, self.bank_side

        def refuse(key, why):
            raise PlantError(
                f"component '{name}': '{key}' follows from the geometry ({why}): leave it "
                "out, or describe that side by the lumped parameters alone"
            )

        self.V = {"hot": P["hot_V"], "cold": P["cold_V"]}
        if geo:
            if P[f"{tube}_V"] is not None:
                refuse(f"{tube}_V", f"the {tube} side flows inside the tubes")
            self.V[tube] = self.tubes.V
        if self.convection != "lumped" and P[f"{tube}_kA"] is not None:
            refuse(f"{tube}_kA", f"convection = '{self.convection}'")
        if self.friction != "lumped":
            if P[f"{tube}_k"] is not None:
                refuse(f"{tube}_k", f"friction = '{self.friction}'")
            if P[f"{tube}_dp_nominal"] != 1e4:
                refuse(f"{tube}_dp_nominal", f"friction = '{self.friction}'")
        if self.bank is not None:
            if P[f"{bank}_V"] is not None:
                refuse(f"{bank}_V", "the gas between the tubes of the bank")
            if P[f"{bank}_kA"] is not None:
                refuse(f"{bank}_kA", "Zukauskas' bank correlation")
            self.V[bank] = self.bank.V_gas
        for side in ("hot", "cold"):
            lumped = not (
                (side == tube and self.convection != "lumped")
                or (side == bank and self.bank is not None)
            )
            if lumped and P[f"{side}_kA"] is None:
                raise PlantError(
                    f"component '{name}': parameter '{side}_kA' [W/K] is required ({side} side "
                    "heat transfer coefficient times area), unless that side is given by "
                    "geometry"
                )
            if self.V[side] is None:
                raise PlantError(
                    f"component '{name}': parameter '{side}_V' [m3] is required ({side} side "
                    "volume), unless that side is given by geometry"
                )
        #: (mass [kg], metal) of the wall's parts (tubes, fins), or () for C_wall
        self.wall_parts = ()
        if geo and self.tubes.has_wall:
            if P["C_wall"] is not None:
                refuse("C_wall", "wall_thickness and wall_material")
            parts = [(self.tubes.wall_mass, self.tubes.metal)]
            if self.bank is not None and self.bank.fin_mass > 0:
                parts.append((self.bank.fin_mass, self.bank.fin_metal))
            self.wall_parts = tuple(parts)
            self.C_wall = sum(m * mt.heat_capacity(300.0) for m, mt in parts)  # a scale
        elif P["C_wall"] is None:
            raise PlantError(
                f"component '{name}': parameter 'C_wall' [J/K] is required (wall heat "
                "capacity), unless the tubes give it (wall_thickness and wall_material)"
            )
        else:
            self.C_wall = P["C_wall"]

    def _bank(self):
        """The ``TubeBank`` of the parameters (it needs the tubes)."""
        P, name = self.params, self.name
        if self.tubes is None:
            raise PlantError(
                f"component '{name}': a tube bank (arrangement, pitches, rows, fins) is the "
                "outside of tubes: give the tubes too (D, length, n_tubes, wall_thickness, "
                "wall_material)"
            )
        missing = [
            k for k in ("arrangement", "pitch_transverse", "pitch_longitudinal", "n_rows")
            if P[k] is None
        ]  # fmt: skip
        if missing:
            raise PlantError(f"component '{name}': a tube bank needs {', '.join(missing)}")
        fins = [P[k] for k in ("fin_height", "fin_thickness", "fin_pitch")]
        if any(v is not None for v in fins) and not all(v is not None and v > 0 for v in fins):
            raise PlantError(
                f"component '{name}': fins need fin_height, fin_thickness and fin_pitch, all > 0"
            )
        D_o = self.tubes.D_out
        if P["pitch_transverse"] <= D_o or P["pitch_longitudinal"] <= 0:
            raise PlantError(
                f"component '{name}': the bank's pitch_transverse ({P['pitch_transverse']:g} "
                f"m) must exceed the tubes' outer diameter ({D_o:g} m)"
            )
        fin_metal = None
        if fins[0] is not None:
            key = P["fin_material"] or P["wall_material"]
            if key is None:
                raise PlantError(f"component '{name}': fins need fin_material (or wall_material)")
            fin_metal = metal(key)
        bank = TubeBank(
            tubes=self.tubes,
            staggered=P["arrangement"] == "staggered",
            S_T=P["pitch_transverse"],
            S_L=P["pitch_longitudinal"],
            n_rows=P["n_rows"],
            frontal_area=P["frontal_area"],
            fin_height=fins[0] or 0.0,
            fin_thickness=fins[1] or 0.0,
            fin_pitch=fins[2],
            fin_metal=fin_metal,
        )
        if bank.finned and bank.fin_pitch <= bank.fin_thickness:
            raise PlantError(f"component '{name}': fin_pitch must exceed fin_thickness")
        if bank.V_gas <= 0:
            raise PlantError(
                f"component '{name}': the bank's tubes fill its frontal area times depth "
                f"(A_front n_rows S_L = {bank.A_front * bank.n_rows * bank.S_L:g} m3): check "
                "frontal_area, the pitches and rows"
            )
        return bank

    def _laws(self, side, n, m_reg):
        """The ``tube_laws.ChannelLaws`` of one side, or None (lumped)."""
        P = self.params
        if side == self.tube_side and self.tubes is not None:
            friction = heat = None
            if self.friction != "lumped":
                friction = TubeFriction(
                    self.tubes, n, self.friction, P["two_phase_friction"], m_reg
                )
            if self.convection != "lumped":
                heat = TubeConvection(self.tubes, n, self.convection, P["x_dryout"], m_reg)
            if friction is None and heat is None:
                return None
            return ChannelLaws(n, friction, heat)
        if side == self.bank_side and self.bank is not None:
            heat = BankConvection(
                self.bank, n, m_reg, P["gas_radiation"], P["wall_emissivity"], P["beam_length"]
            )
            return ChannelLaws(n, None, heat)
        return None

    def wall_capacity(self, T_w):
        """The wall's heat capacity per section [J/K] at T_w [K] (array of n)."""
        if not self.wall_parts:
            return self.C_wall / self.n
        return sum(m * mt.heat_capacity(T_w) for m, mt in self.wall_parts) / self.n

    def wall_energy(self, T_w) -> float:
        """E_wall [J]: C_wall/n sum T_w, or of the metal parts sum_k m_k/n sum e_k(T_w)."""
        if not self.wall_parts:
            return float(self.C_wall / self.n * np.sum(T_w))
        return float(sum(m * np.sum(mt.enthalpy(T_w)) for m, mt in self.wall_parts) / self.n)

    def fluid_ports(self):
        n = self.n
        out = []
        for side, ch in self.channels.items():
            param = f"{side}_k" if self.params[f"{side}_k"] is not None else f"{side}_dp_nominal"
            if side == self.tube_side and self.friction != "lumped":
                param = "D"
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
        branches) each volume's phase is a discrete mode (``dnasim.library.submodels.channel``)."""
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
            M_nom = self.V[side] / self.n * 1e-3
            kA = self.params[f"{side}_kA"]
            if kA is None:  # from geometry: a scale only, 1000 inside, 50 W/(m2 K) outside
                tube = side == self.tube_side
                kA = 1000.0 * self.tubes.A_inner if tube else 50.0 * self.bank.A_out
            if side == self.bank_side and self.bank is not None:
                ch.laws.heat.check_medium(self.side_medium(side), self.name)
            out += ch.variables(
                M_nom,
                M_nom * 1e3,
                1e5,
                1e5,
                max(kA / self.n * DT_Q_NOMINAL, 1.0),
            )
        return out + [Variable("T_w", "K", 300.0, self.n, "wall temperature of section i")]

    def equations(self):
        n, C_i = self.n, self.C_wall / self.n
        eqs = self.channels["hot"].equations() + self.channels["cold"].equations()
        cold_wall = self.cold_wall  # the wall mapping is its own inverse
        if self.wall_parts:
            metals = " + ".join(f"{m / n:g} c_{mt.name}(T_w)" for m, mt in self.wall_parts)
            eqs.append(
                Equation(
                    "wall",
                    size=n,
                    y=lambda i: (f"hot_Q[{i}]", f"cold_Q[{cold_wall[i]}]", f"T_w[{i}]"),
                    yp=lambda i: (f"T_w[{i}]",),
                    doc=f"({metals}) dT_w[i]/dt = hot_Q[i] + cold_Q[j(i)]"
                    " (j(i) = n-1-i counter-flow, i parallel-flow)",
                    unit="W",
                    residual=lambda t, x, xp: (
                        self.wall_capacity(x["T_w"]) * xp["T_w"]
                        - (x["hot_Q"] + x["cold_Q"][cold_wall])
                    ),
                )
            )
            return eqs
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
        mh, mc = self.side_medium("hot"), self.side_medium("cold")
        work = hot.blocks(x, xp, hot.evaluate(mh, x), T_w, mh)
        work.update(cold.blocks(x, xp, cold.evaluate(mc, x), T_w[self.cold_wall], mc))
        return work

    def outputs(self):
        out = [
            Output("hot_T_out", "K", "hot outlet temperature"),
            Output("cold_T_out", "K", "cold outlet temperature"),
            Output("Q_total", "W", "heat from hot fluid to wall"),
        ]
        if self.wall_parts:  # from geometry only: the lumped rows stay as they were
            out.append(Output("E_wall", "J", "wall energy sum m_k e_k(T_w) (reference 0 K)"))
        return out

    def output_values(self, t, x, xp):
        _, _, Th, _, _ = self.channels["hot"].evaluate(self.side_medium("hot"), x)
        _, _, Tc, _, _ = self.channels["cold"].evaluate(self.side_medium("cold"), x)
        out = [Th[-2], Tc[-2], float(np.sum(x["hot_Q"]))]
        if self.wall_parts:
            out.append(self.wall_energy(x["T_w"]))
        return out

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
