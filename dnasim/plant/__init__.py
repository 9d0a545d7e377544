"""Stage 1: a plant as data and as a graph.

``spec`` (PlantSpec, picklable data), ``plantfile`` (TOML -> PlantSpec -> Plant),
``graph`` (PlantGraph: components wired through named nodes), ``plant`` (Plant, the graph
with shorthands), ``signals``, ``plugins``, ``cases`` (sweep cases), ``examples``,
``plantinfo`` (plant.json).

``from dnasim.plant import Plant`` keeps working (the module ``dnasim.plant`` of earlier
versions is now ``dnasim.plant.plant``).
"""

from dnasim.moved_modules import package_getattr

__getattr__ = package_getattr(__name__, "dnasim.plant.plant")
