"""Stage 5: the ``dnasim`` program. ``entry`` (signal handlers first, then the command
line), ``commands`` (run, steady, sweep, check, components, plot, linearize, ...).

``python -m dnasim.cli`` runs it; ``from dnasim.cli import main`` keeps working.
"""

from dnasim.moved_modules import package_getattr

__getattr__ = package_getattr(__name__, "dnasim.cli.commands")
