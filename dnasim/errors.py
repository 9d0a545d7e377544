"""Exception types shared by every layer of dnasim.

This module imports nothing from the rest of the package, so the solver, the
media, the components and the command line can all raise and catch the same
types without depending on each other.
"""


class DnasimError(Exception):
    """Base class of every error dnasim raises on purpose."""


class DAEError(DnasimError):
    """The DAE solver cannot go on: bad input, a singular system, a failed step."""


class ResidualDomainError(DnasimError):
    """A residual evaluation hit a state outside its model's domain.

    Raised from inside ``residual(t, y, yp)`` (for instance when a fluid
    property library refuses a state during a Newton iteration). The solver
    treats it like a failed Newton iteration and cuts the step; only when it
    persists is it reported to the user, with this exception's message.
    """


class PlantError(DnasimError):
    """A plant description is invalid (structure, parameters, connections)."""


class OutputError(DnasimError):
    """A result file cannot be created or written (disk full, file size limit,
    a directory or a foreign file in its place, no permission).

    ``path`` is the file, ``t_reached`` the simulated time [s] of the last whole
    row on disk (None: no row), ``rows`` the number of whole rows on disk.
    This is an environment problem, not a bug: the command line exits with 2.
    """

    def __init__(self, message: str, path=None, t_reached=None, rows: int = 0):
        super().__init__(message)
        self.path = path
        self.t_reached = t_reached
        self.rows = rows
