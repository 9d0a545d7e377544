"""A flow channel: n lumped control volumes in series, the building block of
``Pipe`` and ``HeatExchanger``. Not a component by itself.

Layout (n volumes, faces j = 0..n, volume i between faces i and i+1):

    inlet node --face 0--> [vol 0] --face 1--> [vol 1] ... [vol n-1] --face n--> outlet node

Faces 0..n-1 carry the flow resistance (friction and height); face n joins the
last volume to the outlet node without resistance (its pressure is tied:
p_outlet_node = p_v[n-1]). Every volume has its own state p_v[i] [Pa], h_v[i]
[J/kg]. Flow may go either way through every face; energy is carried upwind of
the actual flow.

Symbols (prefix omitted): m[j] face flows [kg/s] positive from inlet to outlet
(m[0] is the flow into the channel at the inlet port, m[n] the flow out at the
outlet port), M[i] fluid mass [kg], U[i] fluid internal energy [J], Q[i] heat
from fluid to wall [W], T_w the wall temperature next to volume i [K]. The
states along the channel, left to right, are S_0 = inlet node, S_1..S_n = the
volumes, S_{n+1} = outlet node (p, h, and T, rho, u from the medium).
Per volume, with V_i = V/n, kA_i = kA/n, k_i = k/n, dz_i = dz/n:

    face energy flow    E[j] = w(m[j]) h(S_j) - w(-m[j]) h(S_{j+1})           [W]
                        (``physics.energy_in``; E[0] and -E[n] are the port energy flows)
    mass[i]             dM[i]/dt = m[i] - m[i+1]
    energy[i]           dU[i]/dt = E[i] - E[i+1] - Q[i]
    density[i]          M[i] = V_i rho(p_v[i], h_v[i])
    internal_energy[i]  U[i] = M[i] u_i                      ("outlet", fully mixed; default)
                        U[i] = M[i] (u_a + u_i)/2            ("mean", seed eq. 10.12c)
    heat[i]             Q[i] = kA_i LMTD(T_a - T_w, T_i - T_w)     ("lmtd", seed eq. 10.12e)
                        Q[i] = kA_i (T_i - T_w)                   ("outlet", upwind)
                        Q[i] = kA_i ((T_a + T_i)/2 - T_w)         ("mean")
    momentum[i]         p(S_i) - p_v[i] = dp_f(m[i], rho_f) + rho_f g dz_i      (face i)
    outlet_pressure     p(S_{n+1}) = p_v[n-1]

where w is the smooth upwind weight (``physics.upwind_weight``, regularised for
|m| < m_eps = 1e-3 m_nominal, exact outside), and
x_a = (a x(S_i) + b x(S_{i+2}) + c x_i) / (a + b + c), a = w(m[i]), b = w(-m[i+1]),
is the state flowing into volume i (from the left in forward flow, from the
right in reverse flow); c = ``physics.blend_to_own``(a, b) is zero when the
inflow a + b >= m_eps and blends x_a into the volume's own state x_i as the
inflow vanishes (a stagnant or emptying volume exchanges heat at its own
temperature). rho_f = ``physics.upwind_mean`` of the densities on
the two sides of the face. The friction law dp_f is k_i m sqrt(m^2 + m_reg^2)/rho
(``physics.friction_dp``) or, when a nominal pressure drop is given instead of
k, dp_nominal/n m sqrt(m^2 + m_reg^2)/m_nominal^2.

The conserved quantities M and U are the differential states, so mass and
energy are conserved by the integrator to the Newton tolerance; (p, h) of each
volume follow from the algebraic equations density and internal_energy.

Note on "mean": with U = M (u_a + u_i)/2, a jump of the inflow enthalpy moves the
volume's enthalpy the opposite way at once (U cannot jump): after a +100 K inlet
step the outlet of a one-volume pipe jumps down. It is the seed's lumped model,
kept as an option; "outlet" (a mixed volume) is the default.

Phase modes (condensable media; the seed's switch variables, ch. 10). The homogeneous
equation of state rho(p, h) is continuous but kinked on the saturation lines: at 10 bar
d rho/dh|_p jumps from -2.2e-4 (liquid) to -0.075 kg/m3 per J/kg (two-phase). A Newton
iteration whose matrix belongs to one side of the kink diverges on the other, so a
volume that crosses the line inside a step stops the run. With IF97 water (its kernel
evaluates a forced branch: ``dnasim.media.if97_numba.ph_branch_scalar``) each volume
keeps its phase as a discrete mode, mode[i] in {liquid, two-phase, vapour} (none above
the critical pressure), and is evaluated on that branch, continued smoothly past the
line (metastable liquid or vapour; the mixture formula at x < 0 or x > 1). The vector
switch, per volume,

    liquid mode     g[2i]   = h'(p_v[i]) - h_v[i]      (-> two-phase)
    two-phase mode  g[2i]   = h_v[i] - h'(p_v[i])      (-> liquid)
                    g[2i+1] = h''(p_v[i]) - h_v[i]     (-> vapour)
    vapour mode     g[2i+1] = h_v[i] - h''(p_v[i])     (-> two-phase)

is located by the integrator, which changes the mode there and restarts at order 1.
The branches meet on the line, so the state does not jump at a mode change. Modes are
set from the state at the start (``init_phase_modes``). A hysteresis (switching
only some J/kg past the line) was tried and dropped: at fixed M and U the state of a
liquid-filled volume then jumps at the switch, and its pressure with it (a 1 kJ/kg delay
gave a 31 kg/s flow spike at 10 bar).

Other condensable media (CoolProp) have no forced branch: the same switch functions
(g = [h_v - h', h'' - h_v]) then only mark the kink, located with a restart and no
action.
"""

from __future__ import annotations

import numpy as np

from dnasim.model.component import Equation, Switch, Variable
from dnasim.model.physics import (
    LMTD_NUMBA_MIN,
    M_EPS_REL,
    G,
    PropertyArrays,
    blend_to_own,
    friction_dp,
    lmtd,
    lmtd_numpy,
    saturation_enthalpies,
    upwind_mean_weighted,
    upwind_weight,
    upwind_weight_pair,
)

#: the phase switch recomputes a volume's (p, h) from its M and U (``_ph_from_MU``)
#: where the interpolated h_v is within this band [J/kg] of a saturation line, with this
#: many Newton iterations (quadratic from the interpolant's few J/kg: 3 reach round-off)
SWITCH_REFINE_BAND = 2.0e4
SWITCH_REFINE_ITERS = 3

#: phase branch codes (``dnasim.media.if97_numba.ph_branch_scalar``)
AUTO, LIQUID, DOME, VAPOUR = 0, 1, 2, 3


class Channel:
    """Declarations and residual blocks of n volumes in series (see module doc)."""

    def __init__(
        self,
        *,
        prefix: str,
        inlet: str,
        outlet: str,
        n: int,
        V: float,
        k: float | None,
        dz: float,
        kA: float,
        m_nominal: float,
        m_reg: float,
        dT_reg: float,
        internal_energy: str,
        wall: list[str],
        heat_transfer: str = "lmtd",
        dp_nominal: float | None = None,
        kA_exponent: float = 0.0,
        m_kA: float | None = None,
        laws=None,
    ):
        self.prefix = prefix
        self.inlet, self.outlet = inlet, outlet
        self.n = n
        self.V_i = V / n
        self.k_i = None if k is None else k / n
        self.dz_i = dz / n
        self.kA_i = kA / n
        self.m_nominal = m_nominal
        self.m_eps = M_EPS_REL * max(m_nominal, 1e-12)
        self.m_reg = m_reg
        self.dT_reg = dT_reg
        self.mean = internal_energy == "mean"
        self.heat_transfer = heat_transfer
        # friction per face: k law, or nominal-point law dp = c m sqrt(m^2 + m_reg^2)
        self.c_i = None
        if self.k_i is None:
            self.c_i = (dp_nominal or 0.0) / n / max(m_nominal, 1e-12) ** 2
        self.wall = wall  # local name of the wall temperature next to each volume
        # kA_i (|m|/m_kA)^e: the heat transfer coefficient's flow dependence
        # (``walls.flow_scaled_kA``), off for e = 0
        self.kA_exponent = float(kA_exponent)
        self.m_kA = float(m_kA if m_kA is not None else m_nominal)
        #: friction and heat transfer from geometry (``tube_laws.ChannelLaws``), or None
        self.laws = laws
        P = prefix
        self.m, self.M, self.U, self.Q = P + "m", P + "M", P + "U", P + "Q"
        self.pv, self.hv = P + "p_v", P + "h_v"
        self._props = PropertyArrays()
        #: phase modes per volume (set by the component: ``use_phase_modes``)
        self.phase_modes = False
        self.phase_key = P + "phase"

    @property
    def frictionless(self) -> bool:
        if self.laws is not None and self.laws.friction is not None:
            return False
        return (self.k_i if self.k_i is not None else self.c_i) == 0.0

    @property
    def heat_law(self):
        """The heat-transfer law from geometry (``tube_laws``), or None (kA_i)."""
        return None if self.laws is None else self.laws.heat

    # local names of state S_j (0 = inlet node, 1..n = volumes, n+1 = outlet node)
    def state_names(self, j):
        if j == 0:
            return f"{self.inlet}.p", f"{self.inlet}.h"
        if j == self.n + 1:
            return f"{self.outlet}.p", f"{self.outlet}.h"
        return f"{self.pv}[{j - 1}]", f"{self.hv}[{j - 1}]"

    def h_out_inlet(self):
        return f"{self.hv}[0]"

    def h_out_outlet(self):
        return f"{self.hv}[{self.n - 1}]"

    def variables(self, M_nominal, U_nominal, p_nominal, h_nominal, Q_nominal):
        n = self.n
        return [
            Variable(
                self.m, "kg/s", self.m_nominal, n + 1, "flow through face j (0 = inlet, n = outlet)"
            ),
            Variable(self.M, "kg", M_nominal, n, "fluid mass in volume i", min=0.0),
            Variable(self.U, "J", U_nominal, n, "fluid internal energy in volume i"),
            Variable(self.Q, "W", Q_nominal, n, "heat flow from fluid to wall in volume i"),
            Variable(self.pv, "Pa", p_nominal, n, "pressure of volume i"),
            Variable(self.hv, "J/kg", h_nominal, n, "specific enthalpy of volume i"),
        ]

    def equations(self):
        """Six vector equations of n rows and one scalar equation, each with its
        residual: the block of that name in ``x.work`` (``blocks``, computed once per
        evaluation by the component's ``prepare``)."""
        n = self.n
        m, M, U, Q, P = self.m, self.M, self.U, self.Q, self.prefix
        S = self.state_names

        def flows(i):
            return (f"{m}[{i}]", f"{m}[{i + 1}]")

        def inflow(i):  # what the inflow state x_a of volume i reads
            return flows(i) + S(i) + S(i + 2)

        def none(i):
            return ()

        ie_inflow = inflow if self.mean else none
        # kA ~ m^e and the correlations of a heat law read the flows
        kA_flows = flows if self.kA_exponent or self.heat_law is not None else none
        ht_inflow = none if self.heat_transfer == "outlet" else inflow

        def block(key):
            name = P + key
            return lambda t, x, xp: x.work[name]

        return [
            Equation(
                P + "mass",
                size=n,
                y=flows,
                yp=lambda i: (f"{M}[{i}]",),
                doc="dM[i]/dt = m[i] - m[i+1]",
                unit="kg/s",
                residual=block("mass"),
            ),
            Equation(
                P + "energy",
                size=n,
                y=lambda i: flows(i) + (S(i)[1], S(i + 1)[1], S(i + 2)[1], f"{Q}[{i}]"),
                yp=lambda i: (f"{U}[{i}]",),
                doc="dU[i]/dt = E[i] - E[i+1] - Q[i]",
                unit="W",
                residual=block("energy"),
            ),
            Equation(
                P + "density",
                size=n,
                y=lambda i: (f"{M}[{i}]",) + S(i + 1),
                doc="M[i] = V_i rho(p_v[i], h_v[i])",
                unit="kg",
                residual=block("density"),
            ),
            Equation(
                P + "internal_energy",
                size=n,
                y=lambda i: (f"{U}[{i}]", f"{M}[{i}]") + S(i + 1) + ie_inflow(i),
                doc="U[i] = M[i] (u_a + u_i)/2" if self.mean else "U[i] = M[i] u_i",
                unit="J",
                residual=block("internal_energy"),
            ),
            Equation(
                P + "heat",
                size=n,
                y=lambda i: (f"{Q}[{i}]", self.wall[i]) + S(i + 1) + kA_flows(i) + ht_inflow(i),
                doc=f"Q[i] = kA_i dT ({self.heat_transfer})",
                unit="W",
                residual=block("heat"),
            ),
            Equation(
                P + "momentum",
                size=n,
                y=lambda i: S(i) + S(i + 1) + (f"{m}[{i}]",),
                doc="p(S_i) - p_v[i] = dp_f(m[i], rho_f) + rho_f g dz_i",
                unit="Pa",
                residual=block("momentum"),
            ),
            Equation(
                P + "outlet_pressure",
                y=(S(n + 1)[0], f"{self.pv}[{n - 1}]"),
                doc="p(S_{n+1}) = p_v[n-1]",
                unit="Pa",
                residual=block("outlet_pressure"),
            ),
        ]

    def evaluate(self, medium, x):
        """Property arrays (p, h, T, rho, u) of the n + 2 states S_0..S_{n+1}.

        With phase modes (``phase_modes``) each volume is evaluated on its mode's
        branch; the outlet node, whose state is the last volume's, on the last
        volume's branch; the inlet node as usual."""
        p_at, h_at = self._state_positions(x.index)
        p = x.data[p_at]
        h = x.data[h_at]
        T, rho, u = self.state_properties(medium, p, h, x.modes)
        return p, h, T, rho, u

    def state_properties(self, medium, p, h, modes):
        """(T, rho, u) of the n + 2 states at p, h (``evaluate``); ``modes``: the
        component's discrete modes (the phase branch of each volume)."""
        mode = modes.get(self.phase_key) if self.phase_modes else None
        branch = None
        if mode is not None:
            branch = np.concatenate(([0], mode, mode[-1:]))
        return self._props(medium, p, h, branch)

    def _state_positions(self, index):
        """Positions of p and h of the states S_0..S_{n+1} in the component's local
        vector (``index``: its local name -> position map), found once per layout."""
        cached = self.__dict__.get("_positions")
        if cached is None or cached[0] is not index:
            p_at = [index[self.state_names(j)[0]] for j in range(self.n + 2)]
            h_at = [index[self.state_names(j)[1]] for j in range(self.n + 2)]
            cached = self._positions = (index, np.array(p_at), np.array(h_at))
        return cached[1], cached[2]

    def inflow_weights(self, m):
        """(a, b): weights of the left and right neighbour in the inflow state of each
        volume, a = w(m[i]), b = w(-m[i+1])."""
        return upwind_weight(m[:-1], self.m_eps), upwind_weight(-m[1:], self.m_eps)

    def face_energy(self, m, h):
        """E[j] = w(m[j]) h(S_j) - w(-m[j]) h(S_{j+1}) for faces j = 0..n [W]."""
        return upwind_weight(m, self.m_eps) * h[:-1] - upwind_weight(-m, self.m_eps) * h[1:]

    def friction(self, m, rho):
        if self.k_i is not None:
            return friction_dp(self.k_i, m, rho, self.m_reg)
        return self.c_i * m * np.sqrt(m * m + self.m_reg * self.m_reg)

    def blocks(self, x, xp, props, T_wall, medium=None):
        """The residual of each equation of ``equations()`` by its name (prefix
        included): six arrays of n, and "outlet_pressure" an array of one. ``medium``:
        the channel's, needed by laws from geometry (``laws``)."""
        rows = self.__dict__.get("_rows")
        if rows is None:
            rows = self._rows = ChannelRows([self])
        p, h, T, rho, u = props
        bound = self.bind_laws(medium, props, x.modes)
        values = rows.residuals(
            p, h, T, rho, u, x[self.m], x[self.M], x[self.U], x[self.Q], xp[self.M], xp[self.U],
            T_wall, bound,
        )  # fmt: skip
        P = self.prefix
        return {P + name: v for name, v in zip(ChannelRows.NAMES, values, strict=True)}

    def bind_laws(self, medium, props, modes):
        """The laws from geometry at this evaluation's states (``tube_laws.BoundLaws``),
        or None without them; each volume's phase mode (when kept) chooses its
        correlations, the outlet node takes the last volume's."""
        if self.laws is None:
            return None
        if medium is None:  # pragma: no cover - the components pass it
            raise ValueError("Channel.blocks: a channel with laws needs its medium")
        mode = modes.get(self.phase_key) if self.phase_modes else None
        branch = None if mode is None else np.concatenate(([0], mode, mode[-1:]))
        p, h, T, rho, _ = props
        return self.laws.bind(medium, p, h, T, rho, branch)

    def batch_key(self):
        """Channels with equal keys can be evaluated as one (``ChannelRows`` of several):
        the same equations (internal energy, heat transfer law, adiabatic or not,
        friction law); None for a channel that cannot (flow-dependent kA, laws from
        geometry, or ``physics.LMTD_NUMBA_MIN`` volumes or more, whose LMTD is compiled)."""
        if self.kA_exponent or self.laws is not None or self.n >= LMTD_NUMBA_MIN:
            return None
        return (self.mean, self.heat_transfer, self.kA_i == 0.0, self.k_i is not None)

    def use_phase_modes(self) -> None:
        """Evaluate each volume on its phase branch, kept as a discrete mode between
        located crossings (module doc, "Phase modes")."""
        self.phase_modes = True

    def switches(self, medium):
        """The phase switch of the n volumes (see the module doc): one vector Switch."""
        n = self.n
        names = []
        for i in range(n):
            names += [
                f"{self.hv}[{i}] saturated liquid",
                f"{self.hv}[{i}] saturated vapour",
            ]
        if self.phase_modes:
            return [self._mode_switch(medium, names)]

        def g(t, x, xp):
            pv = np.asarray(x[self.pv], dtype=float)
            hv = np.asarray(x[self.hv], dtype=float)
            hl, hvap = saturation_enthalpies(medium, pv)
            out = np.empty(2 * n)
            # above the critical pressure there is no line to cross: a constant sign
            out[0::2] = np.where(np.isfinite(hl), hv - hl, 1.0)
            out[1::2] = np.where(np.isfinite(hvap), hvap - hv, 1.0)
            return out

        return [
            Switch(
                f"{self.prefix}phase",
                g,
                direction=0,
                size=2 * n,
                restart=True,
                names=names,
                kink=True,
                doc="crossing of the saturated-liquid / saturated-vapour line, per volume",
            )
        ]

    # ------------------------------------------------------------------ phase modes
    def _mode_switch(self, medium, names):
        n = self.n

        def g(t, x, xp):
            mode = x.modes.get(self.phase_key)
            if mode is None:
                return np.ones(2 * n)
            M = U = None
            if not self.mean:  # U = M u: (p, h) near a line recomputed from M and U
                M, U = x[self.M], x[self.U]
            return phase_switch_values(medium, mode, x[self.pv], x[self.hv], M, U, self.V_i)

        def action(t, x, xp, which):
            x.modes[self.phase_key] = toggle_phase_modes(x.modes[self.phase_key], which)

        return Switch(
            f"{self.prefix}phase",
            g,
            direction=-1,
            action=action,
            size=2 * n,
            restart=True,
            names=names,
            rearm=True,
            doc="phase mode of each volume: liquid <-> two-phase at h', two-phase <-> vapour "
            "at h''",
        )

    def _ph_from_MU(self, medium, M, U, p, h, mode):
        """(p, h) of volumes from their M and U on their mode's branch (``ph_from_MU``)."""
        return ph_from_MU(medium, self.V_i, M, U, p, h, mode)

    def init_phase_modes(self, medium, x) -> bool:
        """Set each volume's phase mode from its state (h < h': liquid, h > h'':
        vapour, else two-phase; supercritical: none). True when the modes changed."""
        if not self.phase_modes:
            return False
        mode = initial_phase_modes(medium, x[self.pv], x[self.hv])
        old = x.modes.get(self.phase_key)
        x.modes[self.phase_key] = mode
        return old is None or not np.array_equal(old, mode)

    def guess(self, x, medium, p_vol, h_vol, m_guess):
        """Fill guesses from volume states (arrays of n), uniform flow, Q = 0.

        The inlet node must already hold its guess; the outlet node gets the last
        volume's state. Returns T of the n volumes."""
        p_vol = np.asarray(p_vol, dtype=float)
        h_vol = np.asarray(h_vol, dtype=float)
        x[self.pv] = p_vol
        x[self.hv] = h_vol
        x[f"{self.outlet}.p"] = p_vol[-1]
        x[f"{self.outlet}.h"] = h_vol[-1]
        _, _, T, rho, u = self.evaluate(medium, x)
        x[self.m] = m_guess
        a, b = self.inflow_weights(np.full(self.n + 1, float(m_guess)))
        c = blend_to_own(a, b, self.m_eps)
        u_a = (a * u[:-2] + b * u[2:] + c * u[1:-1]) / (a + b + c)
        x[self.M] = self.V_i * rho[1:-1]
        x[self.U] = self.V_i * rho[1:-1] * (0.5 * (u_a + u[1:-1]) if self.mean else u[1:-1])
        x[self.Q] = 0.0
        return T[1:-1]


def ph_from_MU(medium, V_i, M, U, p, h, mode):
    """(p, h) [Pa, J/kg] of volumes on their mode's branch from their mass M [kg] and
    internal energy U [J] in a volume V_i [m3]: Newton on rho(p, h) = M/V_i, u(p, h) = U/M
    from (p, h).

    Why the phase switch evaluates h this way near a line: between the ends of a
    step the integrator's interpolant of the algebraic p_v, h_v is not consistent
    with its interpolant of M, U, and the crossing located on h_v is off. Measured
    on tests/field/condensing_pipe.toml: a volume switched to liquid at its crossing
    located on h_v was, consistently with its M and U, 11 J/kg inside the liquid
    region; the restart's consistent state jumped there, the flows of the liquid
    column with it (-3.2 and +3.9 kg/s against 1 kg/s), and the volume crossed back
    4e-7 s later. u = h - p/rho, so du/dp = -1/rho + p rho_p/rho^2 and
    du/dh = 1 + p rho_h/rho^2."""
    rho_target = M / V_i
    u_target = U / np.where(M > 0.0, M, 1.0)
    for _ in range(SWITCH_REFINE_ITERS):
        st = medium.states(p, h, branch=mode, check=False)
        rho, rp, rh = st.rho, st.drho_dp_h, st.drho_dh_p
        up = -1.0 / rho + p * rp / rho**2
        uh = 1.0 + p * rh / rho**2
        f1 = rho - rho_target
        f2 = st.u - u_target
        det = rp * uh - rh * up
        ok = np.isfinite(det) & (det != 0.0) & st.ok
        dp = np.where(ok, (f1 * uh - rh * f2) / np.where(ok, det, 1.0), 0.0)
        dh = np.where(ok, (rp * f2 - up * f1) / np.where(ok, det, 1.0), 0.0)
        p, h = p - dp, h - dh
    return p, h


def phase_switch_values(medium, mode, pv, hv, M, U, V_i):
    """The phase switch functions g (2n) of n volumes in their phase modes ``mode``
    (module doc, "Phase modes"), at pressures pv [Pa] and enthalpies hv [J/kg]; where
    hv is within ``SWITCH_REFINE_BAND`` of a line and the volumes' mass M [kg] and
    internal energy U [J] are given (U = M u), (p, h) from M and U (``ph_from_MU``)."""
    n = len(mode)
    out = np.ones(2 * n)
    pv = np.array(pv, dtype=float).reshape(n)
    hv = np.array(hv, dtype=float).reshape(n)
    hl, hvap = saturation_enthalpies(medium, pv)
    near = (np.abs(hv - hl) < SWITCH_REFINE_BAND) | (np.abs(hv - hvap) < SWITCH_REFINE_BAND)
    if near.any() and M is not None:
        M = np.asarray(M, dtype=float).reshape(n)[near]
        U = np.asarray(U, dtype=float).reshape(n)[near]
        pv[near], hv[near] = ph_from_MU(medium, V_i, M, U, pv[near], hv[near], mode[near])
        hl, hvap = saturation_enthalpies(medium, pv)
    sub = np.isfinite(hl)
    liq, dome, vap = (mode == LIQUID) & sub, (mode == DOME) & sub, (mode == VAPOUR) & sub
    lo = out[0::2]
    hi = out[1::2]
    lo[liq] = (hl - hv)[liq]  # liquid -> dome at h'
    lo[dome] = (hv - hl)[dome]  # dome -> liquid at h'
    hi[dome] = (hvap - hv)[dome]  # dome -> vapour at h''
    hi[vap] = (hv - hvap)[vap]  # vapour -> dome at h''
    return out


def toggle_phase_modes(mode, which):
    """The modes after the crossings ``which`` (indices into the switch functions of
    ``phase_switch_values``: 2i the saturated-liquid line of volume i, 2i + 1 its
    saturated-vapour line) [a new array]."""
    mode = np.array(mode, copy=True)
    for k in np.atleast_1d(which):
        i, line = divmod(int(k), 2)
        if line == 0:
            mode[i] = DOME if mode[i] == LIQUID else LIQUID
        else:
            mode[i] = DOME if mode[i] == VAPOUR else VAPOUR
    return mode


def initial_phase_modes(medium, pv, hv):
    """Phase mode of each volume from its state: h < h' liquid, h > h'' vapour, else
    two-phase; above the critical pressure none (AUTO)."""
    hv = np.asarray(hv, dtype=float)
    hl, hvap = saturation_enthalpies(medium, np.asarray(pv, dtype=float))
    mode = np.where(hv < hl, LIQUID, np.where(hv > hvap, VAPOUR, DOME))
    return np.where(np.isfinite(hl), mode, AUTO).astype(np.int64)


class ChannelRows:
    """The residual blocks of the module doc, vectorised over one channel or over several
    alike channels (equal ``Channel.batch_key``) laid end to end.

    The arrays handed to ``residuals`` hold the channels one after the other: the states
    S_0..S_{n+1} of each (p, h, T, rho, u), its n + 1 face flows m, its n volumes (M,
    U, Q, dM/dt, dU/dt, T_wall). The index sets below pick, for every face, its left and
    right state, and for every volume its inflow and outflow face and its left, own and
    right state; for one channel they are slices (h[:-1], h[1:], ...). The per-channel
    constants (V_i, k_i or c_i, dz_i, kA_i, m_eps, m_reg, dT_reg) are numbers for one
    channel and arrays over the faces or volumes for several. Every element goes through
    the same operations in either case, so a channel's rows are the same to the bit alone
    and in a batch (tests/test_channel_batch.py)."""

    NAMES = (
        "mass",
        "energy",
        "density",
        "internal_energy",
        "heat",
        "momentum",
        "outlet_pressure",
    )

    def __init__(self, channels):
        ch = channels[0]
        self.mean, self.heat_transfer = ch.mean, ch.heat_transfer
        self.friction_k = ch.k_i is not None
        self.kA_exponent, self.m_kA = ch.kA_exponent, ch.m_kA
        self.adiabatic = ch.kA_i == 0.0 and not ch.kA_exponent and ch.heat_law is None
        #: laws from geometry (one channel only: ``Channel.batch_key`` is None with them)
        self.friction_law = ch.laws is not None and ch.laws.friction is not None
        self.heat_law = ch.heat_law is not None
        if len(channels) == 1:
            self.face_left, self.face_right = slice(None, -1), slice(1, None)
            self.v_in, self.v_out = slice(None, -1), slice(1, None)
            self.left, self.own, self.right = slice(None, -2), slice(1, -1), slice(2, None)
            self.last, self.outlet_node = slice(-2, -1), slice(-1, None)
            self.V_i, self.k_i, self.c_i = ch.V_i, ch.k_i, ch.c_i
            self.dz_i, self.kA_i, self.m_reg, self.dT_reg = ch.dz_i, ch.kA_i, ch.m_reg, ch.dT_reg
            self.eps_face = self.eps_volume = ch.m_eps
            self.lmtd = lmtd  # compiled from LMTD_NUMBA_MIN volumes on
            return
        if len({c.batch_key() for c in channels}) != 1 or None in {c.batch_key() for c in channels}:
            raise ValueError("ChannelRows: channels with different equations")
        idx = {k: [] for k in ("fl", "fr", "vi", "vo", "l", "o", "r", "last", "on")}
        s0 = f0 = 0  # first state and first face of the channel
        for c in channels:
            n, vol = c.n, np.arange(c.n)
            idx["fl"].append(s0 + np.arange(n + 1))
            idx["fr"].append(s0 + 1 + np.arange(n + 1))
            idx["vi"].append(f0 + vol)
            idx["vo"].append(f0 + 1 + vol)
            idx["l"].append(s0 + vol)
            idx["o"].append(s0 + 1 + vol)
            idx["r"].append(s0 + 2 + vol)
            idx["last"].append([s0 + n])
            idx["on"].append([s0 + n + 1])
            s0 += n + 2
            f0 += n + 1
        cat = {k: np.concatenate(v).astype(np.intp) for k, v in idx.items()}
        self.face_left, self.face_right = cat["fl"], cat["fr"]
        self.v_in, self.v_out = cat["vi"], cat["vo"]
        self.left, self.own, self.right = cat["l"], cat["o"], cat["r"]
        self.last, self.outlet_node = cat["last"], cat["on"]

        def per_volume(attr):
            return np.concatenate([np.full(c.n, getattr(c, attr)) for c in channels])

        self.V_i, self.dz_i, self.kA_i = per_volume("V_i"), per_volume("dz_i"), per_volume("kA_i")
        self.m_reg, self.dT_reg = per_volume("m_reg"), per_volume("dT_reg")
        self.k_i = per_volume("k_i") if self.friction_k else None
        self.c_i = None if self.friction_k else per_volume("c_i")
        self.eps_volume = per_volume("m_eps")
        self.eps_face = np.concatenate([np.full(c.n + 1, c.m_eps) for c in channels])
        # numpy's, as each channel alone (fewer than LMTD_NUMBA_MIN volumes: batch_key)
        self.lmtd = lmtd_numpy

    def residuals(self, p, h, T, rho, u, m, M, U, Q, dM, dU, T_wall, laws=None):
        """The seven blocks of ``NAMES`` (module doc), in that order. ``laws``: the
        channel's laws from geometry bound to these states (``tube_laws.BoundLaws``;
        friction, static head and UA instead of k_i and kA_i), or None."""
        # the upwind weights of every face, once: wp = w(m[j]), wm = w(-m[j])
        wp, wm = upwind_weight_pair(m, self.eps_face)
        E = wp * h[self.face_left] - wm * h[self.face_right]  # face_energy
        mass = dM - (m[self.v_in] - m[self.v_out])
        energy = dU - (E[self.v_in] - E[self.v_out] - Q)
        own = self.own
        density = M - self.V_i * rho[own]
        a, b = wp[self.v_in], wm[self.v_out]  # inflow_weights
        # no heat transfer (kA = 0, adiabatic): Q[i] = kA_i dT = 0 needs no dT (Q - 0 dT
        # is Q for every finite dT)
        if self.mean or (self.heat_transfer != "outlet" and not self.adiabatic):
            c = blend_to_own(a, b, self.eps_volume)
            s = a + b + c
            T_a = (a * T[self.left] + b * T[self.right] + c * T[own]) / s
        if self.mean:
            u_a = (a * u[self.left] + b * u[self.right] + c * u[own]) / s
            internal = U - M * 0.5 * (u_a + u[own])
        else:
            internal = U - M * u[own]
        T_i = T[own]
        if self.adiabatic:
            dT = 0.0
        elif self.heat_transfer == "lmtd":
            dT = self.lmtd(T_a - T_wall, T_i - T_wall, self.dT_reg)
        elif self.heat_transfer == "outlet":
            dT = T_i - T_wall
        else:  # "mean"
            dT = 0.5 * (T_a + T_i) - T_wall
        kA = self.kA_i
        if self.heat_law:
            kA = laws.conductance(m[self.v_in], m[self.v_out], T_wall)
        elif self.kA_exponent:
            from dnasim.library.submodels.walls import flow_scaled_kA

            mv = 0.5 * (m[self.v_in] + m[self.v_out])
            kA = flow_scaled_kA(kA, mv, self.m_kA, self.kA_exponent, self.m_reg)
        heat = Q - kA * dT
        mf = m[self.v_in]
        rho_f = upwind_mean_weighted(a, wm[self.v_in], rho[self.left], rho[own])
        rho_head = rho_f
        if self.friction_law:
            friction = laws.friction(mf, a, wm[self.v_in])
            rho_head = laws.head_density(a, wm[self.v_in])
        elif self.friction_k:
            friction = friction_dp(self.k_i, mf, rho_f, self.m_reg)
        else:
            friction = self.c_i * mf * np.sqrt(mf * mf + self.m_reg * self.m_reg)
        momentum = p[self.left] - p[own] - friction - rho_head * G * self.dz_i
        outlet_pressure = p[self.outlet_node] - p[self.last]
        return mass, energy, density, internal, heat, momentum, outlet_pressure
