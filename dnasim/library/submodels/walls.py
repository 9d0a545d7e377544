"""Walls: heat storage with an outer boundary, radial conduction in layers, a heat
flux input, and the flow dependence of a heat transfer coefficient. Not components
by themselves: ``Pipe`` (and ``Channel``) call them.

Wall of one flow volume i (of n; length l_i = length/n, heat capacity
C_i = C_wall/n [J/K]), with N radial nodes k = 0..N-1:

* lumped wall (layers = 0): one node, N = 1;
* layered wall (layers = L >= 1): N = L + 1 nodes at the radii
  r_k = r_in + k (r_out - r_in)/L [m], node 0 on the inner surface (the temperature
  T_w the fluid sees), node L on the outer surface. Between nodes k and k+1 the
  cylindrical shell conducts with the exact steady conductance

      G_k = 2 pi lambda l_i / ln(r_{k+1}/r_k)                                  [W/K]

  so that in steady state the layers in series give exactly the shell's
  resistance sum_k 1/G_k = ln(r_out/r_in)/(2 pi lambda l_i). Shell k holds the
  share (r_{k+1}^2 - r_k^2)/(r_out^2 - r_in^2) of C_i, half of it in each of its
  two nodes.

Node balances [W] (Q[i] the heat from the fluid to the wall, ``Channel``):

    C_k dT_k/dt = G_{k-1} (T_{k-1} - T_k) - G_k (T_k - T_{k+1})
                  + Q[i]                                          (k = 0)
                  + Q_o,i                                         (k = N-1, outer boundary)

Outer boundary of the outer node, heat into the wall Q_o,i [W]:

    none         Q_o,i = 0 (adiabatic outside)
    convection   Q_o,i = kA_outer/n (T_outer(t) - T_{N-1})     (T_outer and kA_outer given)
    heat flux    Q_o,i = Q_outer(t)/n                           (Q_outer given; may be
                                                                 combined with convection)
    temperature  T_{N-1} = T_outer(t)                           (T_outer without kA_outer:
                 the node holds no heat; the heat passing it leaves the plant)

The accumulator Q_passed [J] integrates the heat leaving the wall through its
outer surface (``Pipe``'s sign: heat leaving the plant), d Q_passed/dt =
-sum_i Q_o,i, or with a fixed outer temperature the heat conducted into the
fixed nodes. So: d(U_fluid + E_wall)/dt = port energy flows - dQ_passed/dt,
with E_wall = sum over the nodes that store heat of C_k T_k.

A wall of a metal (``metal``, a ``dnasim.correlations.metals.Metal``: a pipe from
geometry): C_wall is then the wall's mass [kg], node k holds the mass share m_k and
stores m_k e(T_k) (e = ``Metal.enthalpy``, de/dT = c(T)), so its balance reads
m_k c(T_k) dT_k/dt = ...; the conductances are G_k lambda((T_k + T_{k+1})/2) with
G_k computed at lambda = 1 W/(m K).

Flow-dependent heat transfer coefficient (the nominal-point scaling of a
turbulent convective coefficient, alpha ~ Re^0.8 at fixed geometry and fluid):

    kA(m) = kA_nom (sqrt(m^2 + m_reg^2)/m_nom)^e                              [W/K]

(``flow_scaled_kA``; the regularisation m_reg keeps kA > 0 and smooth at m = 0).
"""

from __future__ import annotations

import math

import numpy as np

from dnasim.core.errors import PlantError
from dnasim.model.component import Equation, Variable


def flow_scaled_kA(kA_nom, m, m_nom, exponent, m_reg):
    """kA_nom (sqrt(m^2 + m_reg^2)/m_nom)^exponent [W/K] (see the module doc)."""
    m = np.asarray(m, dtype=float)
    return kA_nom * (np.sqrt(m * m + m_reg * m_reg) / m_nom) ** exponent


def shell_conductance(lam, length, r_a, r_b):
    """Steady conductance of a cylindrical shell r_a..r_b [m] of length [m] and
    conductivity lam [W/(m K)]: 2 pi lam length / ln(r_b/r_a) [W/K]."""
    return 2.0 * math.pi * lam * length / math.log(r_b / r_a)


class WallModel:
    """The wall of the n volumes of a pipe (see the module doc).

    Local names: ``T_w[i]`` the inner node of volume i (the Pipe's variable),
    ``T_wl[i*(N-1) + k-1]`` node k >= 1, ``Q[i]`` the fluid's heat to the wall,
    ``Q_passed`` the accumulator.
    """

    def __init__(
        self,
        *,
        owner: str,
        n: int,
        C_wall: float,
        layers: int = 0,
        r_in: float | None = None,
        r_out: float | None = None,
        length: float | None = None,
        conductivity: float | None = None,
        T_outer=None,
        kA_outer: float | None = None,
        Q_outer=None,
        param_at=None,
        metal=None,
    ):
        self.owner, self.n, self.layers = owner, n, int(layers)
        self.metal = metal
        if metal is not None:
            conductivity = 1.0  # G_k per unit conductivity; lambda(T) at run time
        self.N = self.layers + 1
        self.T_outer, self.kA_outer, self.Q_outer = T_outer, kA_outer, Q_outer
        self.param_at = param_at
        self.fixed_outer = T_outer is not None and kA_outer is None
        self.convection = T_outer is not None and kA_outer is not None
        if self.fixed_outer and Q_outer is not None:
            raise PlantError(
                f"component '{owner}': a fixed outer temperature (T_outer without kA_outer) "
                "leaves no room for a heat flux Q_outer; give kA_outer for convection to "
                "T_outer, or leave out T_outer"
            )
        if kA_outer is not None and T_outer is None:
            raise PlantError(f"component '{owner}': kA_outer needs T_outer (the outer fluid's T)")
        C_i = C_wall / n
        if self.layers:
            missing = [
                k
                for k, v in (
                    ("r_in", r_in),
                    ("r_out", r_out),
                    ("length", length),
                    ("wall_conductivity", conductivity),
                )
                if v is None
            ]
            if missing:
                raise PlantError(
                    f"component '{owner}': a layered wall (wall_layers = {layers}) needs "
                    f"{', '.join(missing)}"
                )
            if not r_out > r_in > 0:
                raise PlantError(
                    f"component '{owner}': the wall needs 0 < r_in < r_out (got r_in = {r_in:g} m, "
                    f"r_out = {r_out:g} m)"
                )
            r = np.linspace(r_in, r_out, self.N)
            l_i = length / n
            self.G = np.array(
                [shell_conductance(conductivity, l_i, r[k], r[k + 1]) for k in range(self.layers)]
            )
            share = (r[1:] ** 2 - r[:-1] ** 2) / (r_out**2 - r_in**2)
            C = np.zeros(self.N)
            C[:-1] += 0.5 * share * C_i
            C[1:] += 0.5 * share * C_i
        else:
            self.G = np.zeros(0)
            C = np.array([C_i])
        if self.fixed_outer:
            C[-1] = 0.0  # the fixed node's heat is outside the plant
        self.C = C
        if not self.fixed_outer and np.any(C <= 0):
            raise PlantError(
                f"component '{owner}': a wall with an outer boundary needs C_wall > 0 (heat "
                "capacity of the wall)"
            )

    # ------------------------------------------------------------ names
    def node(self, i: int, k: int) -> str:
        if k == 0:
            return f"T_w[{i}]"
        return f"T_wl[{i * (self.N - 1) + k - 1}]"

    def variables(self, T_nominal: float = 300.0, Q_nominal: float = 1.0):
        out = []
        if self.N > 1:
            out.append(
                Variable("T_wl", "K", T_nominal, self.n * (self.N - 1), "outer wall node temps")
            )
        out.append(
            Variable(
                "Q_passed",
                "J",
                Q_nominal,
                doc="heat leaving the wall through its outer surface, integral over t",
                accumulator=True,
            )
        )
        return out

    def equations(self):
        """The node balances, then "heat_passed". A lumped wall (N = 1) is one vector
        equation "wall" over the n volumes. A layered wall is N scalar equations
        per volume, "wall[i]" (inner node) and "wall[i,k]", volume by volume, so
        that one volume's nodes are adjacent rows (the row order the solver's
        matching and band ordering start from; a node-by-node order of vector
        equations would change the pivot order and so the run's rounding)."""
        N = self.N
        eqs = []
        node_doc = "C_k dT_k/dt = conduction in - out (+ Q fluid, + outer)"
        if N == 1:
            if self.fixed_outer:
                eqs.append(
                    Equation(
                        "wall",
                        size=self.n,
                        y=lambda i: (self.node(i, 0),),
                        unit="K",
                        doc="T = T_outer(t)",
                        residual=lambda t, x, xp: self._fixed_residual(t, x, 0, slice(None)),
                    )
                )
            else:
                eqs.append(
                    Equation(
                        "wall",
                        size=self.n,
                        y=lambda i: self._node_dependencies(i, 0),
                        yp=lambda i: (self.node(i, 0),),
                        unit="W",
                        doc=node_doc,
                        residual=lambda t, x, xp: self._node_residual(t, x, xp, 0, slice(None)),
                    )
                )
        for i in range(self.n if N > 1 else 0):
            for k in range(N):
                name = f"wall[{i}]" if k == 0 else f"wall[{i},{k}]"
                me = self.node(i, k)
                if self.fixed_outer and k == N - 1:
                    eqs.append(
                        Equation(
                            name,
                            y=(me,),
                            unit="K",
                            doc="T = T_outer(t)",
                            residual=lambda t, x, xp, i=i, k=k: self._fixed_residual(t, x, k, i),
                        )
                    )
                    continue
                eqs.append(
                    Equation(
                        name,
                        y=self._node_dependencies(i, k),
                        yp=(me,),
                        unit="W",
                        doc=node_doc,
                        residual=lambda t, x, xp, i=i, k=k: self._node_residual(t, x, xp, k, i),
                    )
                )
        dep = [self.node(i, N - 1) for i in range(self.n)]
        if self.fixed_outer:
            dep += [self.node(i, N - 2) for i in range(self.n)] if N > 1 else []
            dep += [f"Q[{i}]" for i in range(self.n)] if N == 1 else []
        eqs.append(
            Equation(
                "heat_passed",
                y=tuple(dep),
                yp=("Q_passed",),
                unit="W",
                doc="dQ_passed/dt = heat out through the outer surface",
                residual=lambda t, x, xp: xp["Q_passed"] - self._heat_out(t, x),
            )
        )
        return eqs

    def _node_dependencies(self, i, k):
        y = [self.node(i, k)]
        if k > 0:
            y.append(self.node(i, k - 1))
        if k < self.N - 1:
            y.append(self.node(i, k + 1))
        if k == 0:
            y.append(f"Q[{i}]")
        return tuple(y)

    # ---------------------------------------------------------- residual
    def node_temperature(self, v, k: int, i=slice(None)):
        """T_k (or dT_k/dt from xp) [K] of volume i (an int) or of all n (a slice)."""
        if k == 0:
            return np.asarray(v["T_w"], dtype=float)[i]
        return np.asarray(v["T_wl"], dtype=float).reshape(self.n, self.N - 1)[i, k - 1]

    def _G(self, k, Ta, Tb):
        """Conductance of shell k [W/K] between nodes at Ta and Tb [K]."""
        if self.metal is None:
            return self.G[k]
        return self.G[k] * self.metal.conductivity(0.5 * (Ta + Tb))

    def node_flow(self, x, k: int, i=slice(None)):
        """Net heat into node k [W] by conduction (and Q[i] at k = 0), of volume i (an
        int) or of all n (a slice)."""
        flow = np.zeros(self.n)[i]
        if k < self.N - 1:  # to node k+1
            Ta, Tb = self.node_temperature(x, k, i), self.node_temperature(x, k + 1, i)
            flow -= self._G(k, Ta, Tb) * (Ta - Tb)
        if k > 0:  # from node k-1
            Ta, Tb = self.node_temperature(x, k - 1, i), self.node_temperature(x, k, i)
            flow += self._G(k - 1, Ta, Tb) * (Ta - Tb)
        if k == 0:
            flow += np.asarray(x["Q"], dtype=float)[i]
        return flow

    def _node_residual(self, t, x, xp, k, i):
        C = self.C[k]
        if self.metal is not None:
            C = C * self.metal.heat_capacity(self.node_temperature(x, k, i))
        r = C * self.node_temperature(xp, k, i) - self.node_flow(x, k, i)
        if k == self.N - 1:
            r -= self.outer_heat_in(t, self.node_temperature(x, k, i))
        return r

    def _fixed_residual(self, t, x, k, i):
        return self.node_temperature(x, k, i) - self.param_at("T_outer", t)

    def _heat_out(self, t, x) -> float:
        """Heat leaving through the outer surface [W]: into the fixed outer nodes, or
        minus the outer heat into the wall."""
        if self.fixed_outer:
            return float(np.sum(self.node_flow(x, self.N - 1)))
        return -float(np.sum(self.outer_heat_in(t, self.node_temperature(x, self.N - 1))))

    def temperatures(self, x) -> np.ndarray:
        """Node temperatures, shape (n, N) [K]."""
        T = np.empty((self.n, self.N))
        T[:, 0] = x["T_w"]
        if self.N > 1:
            T[:, 1:] = np.asarray(x["T_wl"]).reshape(self.n, self.N - 1)
        return T

    def outer_heat_in(self, t, T_outer_node):
        """Q_o,i [W] into the outer nodes (convection and heat flux), at the outer
        node temperatures T_outer_node [K] (one volume's or all n)."""
        q = np.zeros(np.shape(T_outer_node))
        if self.convection:
            q += self.kA_outer / self.n * (self.param_at("T_outer", t) - T_outer_node)
        if self.Q_outer is not None:
            q += self.param_at("Q_outer", t) / self.n
        return q

    def energy(self, x) -> float:
        """E_wall = sum C_k T_k [J] (nodes that store heat; of a metal sum m_k e(T_k))."""
        T = self.temperatures(x)
        if self.metal is not None:
            return float(np.sum(self.C[None, :] * self.metal.enthalpy(T)))
        return float(np.sum(self.C[None, :] * T))

    def guess(self, t0, x, T_inner):
        """Nodes at T_inner (or T_outer for a fixed outer node)."""
        T_inner = np.asarray(T_inner, dtype=float)
        x["T_w"] = T_inner
        if self.N > 1:
            T = np.repeat(T_inner[:, None], self.N - 1, axis=1)
            if self.fixed_outer:
                T_o = self.param_at("T_outer", t0)
                frac = np.arange(1, self.N) / (self.N - 1)
                T = T_inner[:, None] + (T_o - T_inner[:, None]) * frac[None, :]
            x["T_wl"] = T.reshape(-1)
        elif self.fixed_outer:
            x["T_w"] = self.param_at("T_outer", t0)
        x["Q_passed"] = 0.0
