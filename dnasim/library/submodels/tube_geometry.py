"""Tubes and tube banks described by their geometry (issue 22): the areas, volumes,
masses and conduction resistances a component derives from a datasheet-like
description. Not components by themselves: ``Pipe``, ``HeatExchanger`` and
``Condenser`` build them from their parameters, and ``dnasim.library.submodels.tube_laws``
evaluates the friction and heat-transfer correlations on them.

Tubes (``Tubes``): n_tubes parallel round tubes of inner diameter D [m] and length L
[m] each, wall thickness s [m] (outer diameter D_o = D + 2 s), wall material (a
``dnasim.correlations.metals`` name), inner roughness k_s [m]:

    flow area          A = n_tubes pi D^2 / 4                                   [m2]
    fluid volume       V = A L                                                  [m3]
    inner surface      A_i = n_tubes pi D L,   outer surface A_o = n_tubes pi D_o L [m2]
    wall mass          m_w = rho_metal n_tubes pi (D_o^2 - D^2)/4 L             [kg]
    wall conduction    R_wall = ln(D_o/D) / (2 pi lambda n_tubes L)             [K/W]

The lumped wall of a volume has one temperature T_w: the wall's, at its mean radius
r_m = (D + D_o)/4. Heat passes from the inner surface to it through the inner half of
the wall, R_in = ln(2 r_m/D)/(2 pi lambda n_tubes L), and from it to the outer surface
through R_out = ln(D_o/(2 r_m))/(2 pi lambda n_tubes L) (R_in + R_out = R_wall): the
steady conductances of the two cylindrical half-shells.

Tube banks (``TubeBank``): the outside of the same tubes in cross flow, Zukauskas'
geometry (Incropera et al., 6th ed., Sect. 7.6): arrangement inline or staggered,
transverse pitch S_T and longitudinal pitch S_L [m], n_rows rows in the flow direction,
frontal (duct) area A_front [m2] the gas approaches through (default: the tubes' own,
n_tubes L S_T / n_rows: each row's tube length across a strip S_T wide); optional
annular fins of height h_f, thickness t_f and pitch s_f (centre to centre) [m] of a
material (default the tubes'):

    fins per tube length         N_f = 1 / s_f                                  [1/m]
    fin area (both faces, tip)   A_fin = n_tubes L N_f (2 pi (r_2c^2 - r_1^2)),  r_2c = r_2 + t_f/2
    bare tube between fins       A_base = A_o (1 - t_f N_f)
    outer area                   A_out = A_fin + A_base                         [m2]
    fin mass                     m_f = rho_fin n_tubes L N_f pi (r_2^2 - r_1^2) t_f  [kg]
    gas volume                   V_gas = A_front n_rows S_L - n_tubes L pi D_o^2/4 - m_f/rho_fin
    blocked width per tube       D_eff = D_o + 2 h_f t_f N_f (the fins' share of the
                                 narrowest section: ``tube_laws`` uses it for V_max)
    mean beam length             L_m = 3.6 V_gas / A_o   (Hottel's 3.6 V/A over the tubes)

with r_1 = D_o/2 and r_2 = r_1 + h_f.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from dnasim.core.errors import PlantError
from dnasim.correlations.metals import Metal, metal, metal_names
from dnasim.model.component import Param

#: [m] default inner roughness: commercial (drawn or hot-finished) steel tube, the
#: Moody chart's 0.045 mm
ROUGHNESS_DEFAULT = 4.5e-5


@dataclass(frozen=True)
class Tubes:
    """n_tubes parallel round tubes (module doc). Lengths [m], metal or None (no wall)."""

    D: float
    length: float
    n_tubes: int = 1
    wall_thickness: float = 0.0
    metal: Metal | None = None
    roughness: float = 0.0

    @property
    def A_tube(self) -> float:
        """Flow area of one tube [m2]."""
        return math.pi * self.D * self.D / 4.0

    @property
    def A_flow(self) -> float:
        """Flow area of all tubes [m2]."""
        return self.n_tubes * self.A_tube

    @property
    def V(self) -> float:
        """Fluid volume [m3]."""
        return self.A_flow * self.length

    @property
    def D_out(self) -> float:
        """Outer diameter [m]."""
        return self.D + 2.0 * self.wall_thickness

    @property
    def A_inner(self) -> float:
        """Inner surface of all tubes [m2]."""
        return self.n_tubes * math.pi * self.D * self.length

    @property
    def A_outer(self) -> float:
        """Outer (bare) surface of all tubes [m2]."""
        return self.n_tubes * math.pi * self.D_out * self.length

    @property
    def has_wall(self) -> bool:
        """A wall of some thickness and a material: its mass and conduction count."""
        return self.metal is not None and self.wall_thickness > 0.0

    @property
    def wall_mass(self) -> float:
        """Mass of the tube walls [kg] (0 without a wall)."""
        if not self.has_wall:
            return 0.0
        ring = math.pi / 4.0 * (self.D_out**2 - self.D**2)
        return self.metal.rho * self.n_tubes * ring * self.length

    def _log_ratio(self, part: str) -> float:
        r_i, r_o = self.D / 2.0, self.D_out / 2.0
        r_m = 0.5 * (r_i + r_o)
        ratio = {"inner": r_m / r_i, "outer": r_o / r_m, "whole": r_o / r_i}[part]
        return math.log(ratio)

    def conduction_resistance(self, lam, part: str = "whole"):
        """Steady conduction resistance [K/W] of the tube walls (all tubes, whole length)
        at conductivity lam [W/(m K)] (a number or an array): the whole wall, its inner
        half ("inner": inner surface to the mean radius) or its outer half ("outer")."""
        if not self.has_wall:
            return 0.0 * lam
        return self._log_ratio(part) / (2.0 * math.pi * lam * self.n_tubes * self.length)


@dataclass(frozen=True)
class TubeBank:
    """The outside of ``tubes`` in cross flow (module doc). Lengths [m], areas [m2]."""

    tubes: Tubes
    staggered: bool
    S_T: float
    S_L: float
    n_rows: int
    frontal_area: float | None = None
    fin_height: float = 0.0
    fin_thickness: float = 0.0
    fin_pitch: float | None = None
    fin_metal: Metal | None = None

    @property
    def D_o(self) -> float:
        return self.tubes.D_out

    @property
    def A_front(self) -> float:
        """Frontal area the gas approaches through [m2] (given, or the tubes' own)."""
        if self.frontal_area is not None:
            return self.frontal_area
        t = self.tubes
        return t.n_tubes * t.length * self.S_T / self.n_rows

    @property
    def finned(self) -> bool:
        return self.fin_pitch is not None and self.fin_height > 0.0 and self.fin_thickness > 0.0

    @property
    def fins_per_length(self) -> float:
        """N_f [1/m]."""
        return 1.0 / self.fin_pitch if self.finned else 0.0

    @property
    def r_1(self) -> float:
        return self.D_o / 2.0

    @property
    def r_2(self) -> float:
        return self.r_1 + self.fin_height

    @property
    def A_fin(self) -> float:
        """Area of all fins [m2] (both faces and the tip, Schmidt's r_2c)."""
        if not self.finned:
            return 0.0
        r2c = self.r_2 + 0.5 * self.fin_thickness
        per_fin = 2.0 * math.pi * (r2c * r2c - self.r_1 * self.r_1)
        return self.tubes.n_tubes * self.tubes.length * self.fins_per_length * per_fin

    @property
    def A_base(self) -> float:
        """Bare tube surface between the fins [m2]."""
        return self.tubes.A_outer * (1.0 - self.fin_thickness * self.fins_per_length)

    @property
    def A_out(self) -> float:
        """Outer heat-transfer area [m2]: fins and bare tube."""
        return self.A_fin + self.A_base

    @property
    def fin_volume(self) -> float:
        """Metal volume of the fins [m3]."""
        if not self.finned:
            return 0.0
        per_fin = math.pi * (self.r_2**2 - self.r_1**2) * self.fin_thickness
        return self.tubes.n_tubes * self.tubes.length * self.fins_per_length * per_fin

    @property
    def fin_mass(self) -> float:
        """Mass of the fins [kg] (0 without fins or without a fin material)."""
        metal = self.fin_metal
        return 0.0 if metal is None else metal.rho * self.fin_volume

    @property
    def D_eff(self) -> float:
        """Width blocked per tube in the narrowest section [m]: D_o plus the fins' share."""
        return self.D_o + 2.0 * self.fin_height * self.fin_thickness * self.fins_per_length

    @property
    def V_gas(self) -> float:
        """Gas volume of the bank [m3]."""
        t = self.tubes
        solid = t.n_tubes * t.length * math.pi * self.D_o**2 / 4.0 + self.fin_volume
        return self.A_front * self.n_rows * self.S_L - solid

    @property
    def beam_length(self) -> float:
        """Mean beam length of the gas between the tubes [m]: 3.6 V_gas / A_o."""
        return 3.6 * self.V_gas / self.tubes.A_outer


def tube_params(length_doc: str = "tube length (geometry)") -> tuple:
    """The parameters that describe tubes (``Tubes``), shared by the components
    built from geometry: D, length, n_tubes, wall_thickness, wall_material, roughness."""
    return (
        Param(
            "D",
            "m",
            None,
            "inner tube diameter: the component from geometry (volume, wall, friction and "
            "heat transfer from correlations; docs/plant_files.md)",
            min=0.0,
        ),
        Param("length", "m", None, length_doc, min=0.0),
        Param("n_tubes", "1", 1, "number of parallel tubes (geometry)", min=1, kind="int"),
        Param(
            "wall_thickness",
            "m",
            None,
            "tube wall thickness (geometry; with wall_material: the wall's mass, heat capacity "
            "c(T) and conduction lambda(T))",
            min=0.0,
        ),
        Param(
            "wall_material",
            "1",
            None,
            "tube wall metal (geometry; dnasim.correlations.metals): " + ", ".join(metal_names()),
            kind="string",
            choices=metal_names(),
        ),
        Param(
            "roughness",
            "m",
            ROUGHNESS_DEFAULT,
            "inner wall roughness (geometry; default 0.045 mm, commercial steel)",
            min=0.0,
        ),
    )


def tubes_from_params(owner: str, P: dict) -> Tubes | None:
    """The ``Tubes`` of a component's parameters (``tube_params``), or None when D is
    not given; PlantError naming the component and parameter for a bad combination."""
    if P.get("D") is None:
        for key in ("wall_thickness", "wall_material"):
            if P.get(key) is not None:
                raise PlantError(
                    f"component '{owner}': parameter '{key}' describes tubes: give their inner "
                    "diameter D and length too (or leave it out for the lumped model)"
                )
        return None
    D, L = P["D"], P.get("length")
    if not D > 0:
        raise PlantError(f"component '{owner}': the inner diameter D must be > 0 m (got {D:g} m)")
    if L is None or not L > 0:
        raise PlantError(
            f"component '{owner}': tubes given by D need their length 'length' > 0 [m]"
        )
    s, name = P.get("wall_thickness"), P.get("wall_material")
    if (s is None) != (name is None):
        given, missing = ("wall_thickness", "wall_material") if name is None else (
            "wall_material", "wall_thickness")  # fmt: skip
        raise PlantError(
            f"component '{owner}': '{given}' needs '{missing}' too (a tube wall is a thickness "
            "of a metal: its mass, heat capacity and conduction)"
        )
    if s is not None and not s > 0:
        raise PlantError(f"component '{owner}': wall_thickness must be > 0 m (got {s:g} m)")
    return Tubes(
        D=float(D),
        length=float(L),
        n_tubes=int(P.get("n_tubes") or 1),
        wall_thickness=float(s or 0.0),
        metal=None if name is None else metal(name),
        roughness=float(P.get("roughness") or 0.0),
    )
