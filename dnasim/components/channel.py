"""A flow channel: n lumped control volumes in series, the building block of
``Pipe`` and ``HeatExchanger``. Not a component by itself.

Layout (n volumes, faces j = 0..n, volume i between faces i and i+1):

    inlet node --face 0--> [vol 0] --face 1--> [vol 1] ... [vol n-1] = outlet node

Each face carries the flow resistance (friction and height), each volume the
storage. The state of the last volume is the outlet node (p, h); the states of
the other volumes are internal variables ``p_v[i]``, ``h_v[i]``. The upstream
state of volume i ("up") is the inlet node for i = 0, else volume i-1.

Symbols (prefix omitted): m[j] face flows [kg/s] (m[0] is the inlet flow,
m[n] the outlet flow), M[i] fluid mass [kg], U[i] fluid internal energy [J],
Q[i] heat from fluid to wall [W], T_w the wall temperature next to volume i [K].
Per volume, with V_i = V/n, kA_i = kA/n, k_i = k/n, dz_i = dz/n:

    mass[i]             dM[i]/dt = m[i] - m[i+1]
    energy[i]           dU[i]/dt = m[i] h_up - m[i+1] h_i - Q[i]
    density[i]          M[i] = V_i rho(p_i, h_i)
    internal_energy[i]  U[i] = M[i] (u_up + u_i)/2        ("mean", seed eq. 10.12c)
                        U[i] = M[i] u_i                    ("outlet", fully mixed)
    heat[i]             Q[i] = kA_i LMTD(T_up - T_w, T_i - T_w)     ("lmtd", seed eq. 10.12e)
                        Q[i] = kA_i (T_i - T_w)                    ("outlet", upwind)
                        Q[i] = kA_i ((T_up + T_i)/2 - T_w)         ("mean")
    momentum[i]         p_up - p_i = k_i m[i] sqrt(m[i]^2 + m_reg^2)/rho_up + rho_up g dz_i

The conserved quantities M and U are the differential states, so mass and
energy are conserved by the integrator to the Newton tolerance; (p, h) of each
volume follow from the algebraic equations density and internal_energy.

Note on "mean": with U = M (u_up + u_i)/2, a jump of the inlet enthalpy moves the
outlet enthalpy the opposite way at once (U cannot jump). This is a property of
the seed's lumped model; use smooth inlet changes, more volumes, or "outlet".
"""

from __future__ import annotations

import numpy as np

from dnasim.components.base import Equation, Variable
from dnasim.components.physics import G, PropertyArrays, friction_dp, lmtd, properties


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
        k: float,
        dz: float,
        kA: float,
        m_nominal: float,
        m_reg: float,
        dT_reg: float,
        internal_energy: str,
        wall: list[str],
        heat_transfer: str = "lmtd",
    ):
        self.prefix = prefix
        self.inlet, self.outlet = inlet, outlet
        self.n = n
        self.V_i = V / n
        self.k_i = k / n
        self.dz_i = dz / n
        self.kA_i = kA / n
        self.m_nominal = m_nominal
        self.m_reg = m_reg
        self.dT_reg = dT_reg
        self.mean = internal_energy == "mean"
        self.heat_transfer = heat_transfer
        self.wall = wall  # local name of the wall temperature next to each volume
        P = prefix
        self.m, self.M, self.U, self.Q = P + "m", P + "M", P + "U", P + "Q"
        self.pv, self.hv = P + "p_v", P + "h_v"
        self._props = PropertyArrays()

    # names of the state of volume i and of its upstream state
    def p_name(self, i):
        return f"{self.outlet}.p" if i == self.n - 1 else f"{self.pv}[{i}]"

    def h_name(self, i):
        return f"{self.outlet}.h" if i == self.n - 1 else f"{self.hv}[{i}]"

    def up(self, i):
        if i == 0:
            return f"{self.inlet}.p", f"{self.inlet}.h"
        return self.p_name(i - 1), self.h_name(i - 1)

    def variables(self, M_nominal, U_nominal, p_nominal, h_nominal, Q_nominal):
        n = self.n
        out = [
            Variable(
                self.m, "kg/s", self.m_nominal, n + 1, "flow through face j (0 = inlet, n = outlet)"
            ),
            Variable(self.M, "kg", M_nominal, n, "fluid mass in volume i"),
            Variable(self.U, "J", U_nominal, n, "fluid internal energy in volume i"),
            Variable(self.Q, "W", Q_nominal, n, "heat flow from fluid to wall in volume i"),
        ]
        if n > 1:
            out += [
                Variable(self.pv, "Pa", p_nominal, n - 1, "pressure of inner volume i"),
                Variable(self.hv, "J/kg", h_nominal, n - 1, "enthalpy of inner volume i"),
            ]
        return out

    def equations(self):
        n = self.n
        m, M, U, Q = self.m, self.M, self.U, self.Q
        eqs = {k: [] for k in ("mass", "energy", "density", "internal_energy", "heat", "momentum")}
        P = self.prefix
        for i in range(n):
            pi, hi = self.p_name(i), self.h_name(i)
            pu, hu = self.up(i)
            mi, mo = f"{m}[{i}]", f"{m}[{i + 1}]"
            eqs["mass"].append(Equation(f"{P}mass[{i}]", y=(mi, mo), yp=(f"{M}[{i}]",)))
            eqs["energy"].append(
                Equation(f"{P}energy[{i}]", y=(mi, mo, hu, hi, f"{Q}[{i}]"), yp=(f"{U}[{i}]",))
            )
            eqs["density"].append(Equation(f"{P}density[{i}]", y=(f"{M}[{i}]", pi, hi)))
            ie = (f"{U}[{i}]", f"{M}[{i}]", pi, hi) + ((pu, hu) if self.mean else ())
            eqs["internal_energy"].append(Equation(f"{P}internal_energy[{i}]", y=ie))
            eqs["heat"].append(
                Equation(f"{P}heat[{i}]", y=(f"{Q}[{i}]", self.wall[i], pu, hu, pi, hi))
            )
            eqs["momentum"].append(Equation(f"{P}momentum[{i}]", y=(pu, pi, hu, mi)))
        return [e for block in eqs.values() for e in block]

    def states(self, x):
        """Pressure and enthalpy of the n volumes, and of the inlet node (arrays)."""
        n = self.n
        p = np.empty(n)
        h = np.empty(n)
        if n > 1:
            p[:-1] = x[self.pv]
            h[:-1] = x[self.hv]
        p[-1] = x[f"{self.outlet}.p"]
        h[-1] = x[f"{self.outlet}.h"]
        return p, h

    def evaluate(self, medium, x):
        """Property arrays: (p, h, T, rho, u) with n + 1 entries, entry 0 = inlet node,
        entry i + 1 = volume i."""
        pv, hv = self.states(x)
        p = np.concatenate(([x[f"{self.inlet}.p"]], pv))
        h = np.concatenate(([x[f"{self.inlet}.h"]], hv))
        T, rho, u = self._props(medium, p, h)
        return p, h, T, rho, u

    def residual_blocks(self, x, xp, props, T_wall):
        """Residuals in the order of ``equations()`` (six blocks of n)."""
        p, h, T, rho, u = props
        m = x[self.m]
        M = x[self.M]
        U = x[self.U]
        Q = x[self.Q]
        dM = xp[self.M]
        dU = xp[self.U]
        mass = dM - (m[:-1] - m[1:])
        energy = dU - (m[:-1] * h[:-1] - m[1:] * h[1:] - Q)
        density = M - self.V_i * rho[1:]
        if self.mean:
            internal = U - M * 0.5 * (u[:-1] + u[1:])
        else:
            internal = U - M * u[1:]
        if self.heat_transfer == "lmtd":
            dT = lmtd(T[:-1] - T_wall, T[1:] - T_wall, self.dT_reg)
        elif self.heat_transfer == "outlet":
            dT = T[1:] - T_wall
        else:  # "mean"
            dT = 0.5 * (T[:-1] + T[1:]) - T_wall
        heat = Q - self.kA_i * dT
        momentum = (
            p[:-1]
            - p[1:]
            - friction_dp(self.k_i, m[:-1], rho[:-1], self.m_reg)
            - rho[:-1] * G * self.dz_i
        )
        return [mass, energy, density, internal, heat, momentum]

    def guess(self, x, medium, p_vol, h_vol, m_guess):
        """Fill guesses from volume states (arrays of n), uniform flow, Q = 0.

        The inlet node must already hold its guess. Returns T (n + 1 entries,
        entry 0 = inlet node)."""
        n = self.n
        p_vol = np.asarray(p_vol, dtype=float)
        h_vol = np.asarray(h_vol, dtype=float)
        if n > 1:
            x[self.pv] = p_vol[:-1]
            x[self.hv] = h_vol[:-1]
        x[f"{self.outlet}.p"] = p_vol[-1]
        x[f"{self.outlet}.h"] = h_vol[-1]
        p = np.concatenate(([x[f"{self.inlet}.p"]], p_vol))
        h = np.concatenate(([x[f"{self.inlet}.h"]], h_vol))
        T, rho, u = properties(medium, p, h)
        x[self.m] = m_guess
        x[self.M] = self.V_i * rho[1:]
        x[self.U] = self.V_i * rho[1:] * (0.5 * (u[:-1] + u[1:]) if self.mean else u[1:])
        x[self.Q] = 0.0
        return T
