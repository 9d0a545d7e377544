"""Engineering correlations: pure, vectorised numpy functions of SI numbers.

Each function states its equation, its source, its range of validity and what it does
outside that range (docs/correlations.md has the overview). Modules:

* ``friction``: Darcy friction factor (laminar, Colebrook, the transition blend), the
  signed single-phase pressure drop, two-phase friction (homogeneous, Friedel),
  void fraction and static head;
* ``heat_transfer``: single-phase heat transfer inside tubes (Gnielinski,
  Dittus-Boelter, laminar, the VDI transition);
* ``boiling``: saturated flow boiling (Chen) with the dry-out limit;
* ``condensation``: condensation inside tubes (Shah 1979);
* ``tube_banks``: gas side of tube banks (Zukauskas) and annular fins (Schmidt);
* ``radiation``: emissivity of H2O/CO2 gas (weighted sum of grey gases), mean beam length;
* ``metals``: lambda(T), c(T), rho of boiler steels and copper.

Nothing here imports the rest of dnasim: a component passes the numbers in.
"""
