"""DrainValve: a ControlValve whose law is the flashing (HEM) law by default."""

from __future__ import annotations

import dataclasses

from dnasim.library.control_valve import ControlValve


class DrainValve(ControlValve):
    """Drain valve (condensate from a heater, a drum, a hotwell or a steam line to a
    lower pressure): the ``ControlValve`` with law = "hem" as the default, so that
    its flow follows the density and the flashing of the actual inlet state.

      m = K z_e phi sqrt(rho_1) g(eps_e p_1),  eps = dp/p_1                     [kg/s]

    rho_1 [kg/m3] is the density of the upstream state (inside the two-phase dome
    the homogeneous mixture's), phi [-] the omega method's factor (homogeneous
    equilibrium flow, API 520 Part I Annex C; ``dnasim.library.submodels.valve_laws``):

      subcooled liquid, p_2 >= p_sat(T_1)   phi = 1: m = K z_e sqrt(rho_1 dp) (Kv law)
      subcooled liquid, p_2 <  p_sat(T_1)   the liquid flashes in the valve: less flow,
                                            choked at p_sat (high subcooling) or below
      two-phase mixture, steam, gas         omega = 1/kappa_s of the equilibrium
                                            state; choked below eta_c(omega) p_1

    So steam or a steam-water mixture reaching the drain passes far less mass than
    condensate at the same pressures (10 bar -> 5 bar, the same K: saturated steam
    passes 1/21 of the flow of condensate at 150 degC and 1/4.6 of saturated water's,
    tests/test_valve_laws.py). The valve is an ideal nozzle for the flashing (no
    pressure recovery, F_L = 1), and the flashing is in equilibrium: through a short
    passage a saturated or slightly subcooled liquid flashes late and passes more
    than the HEM gives (non-equilibrium flashing, Henry and Fauske 1971), so the law
    is conservative (low) there; the
    omega method is within 2.3 % of the exact equilibrium nozzle (IAPWS-95) from
    subcooled liquid to superheated steam. K from ``Kv``, ``Cv``, ``A``
    with ``K_d`` or the nominal point (taken as incompressible), the opening from
    the parameter ``opening`` or the signal ``z`` (a level controller), and every
    other parameter as for ``ControlValve``; ``law = "iec"`` gives the IEC 60534
    liquid/gas equations instead.
    """

    PARAMS = tuple(
        dataclasses.replace(p, default="hem") if p.name == "law" else p for p in ControlValve.PARAMS
    )
