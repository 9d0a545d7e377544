"""Stage 3: consistent initial values (y0, y'0) of a compiled System.

``initial`` (``initial_values``, the entry: ``start = "given" | "steady"``), ``guess``
(the starting point from the components' own guesses and node guesses), ``consistent``
(Newton on the algebraic part), ``steady_state`` (the plant at rest, globalised).

``from dnasim.start import initial_values`` keeps working (the module ``dnasim.start`` of
earlier versions is now ``dnasim.start.initial``).
"""

from dnasim.moved_modules import package_getattr

__getattr__ = package_getattr(__name__, "dnasim.start.initial")
