"""Output sinks: where ``simulate`` streams the output rows while the solver runs.

Contract: ``open(names, units)`` once before the first row (names in
``System.output_names()`` order, units name -> unit string), ``write(t, row)``
per output point (t [s], row: ndarray in names order), ``close()`` once at the
end, also after a failure.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["CSVSink", "OutputRows", "RESTART_COLUMN"]

#: last output column: 1 on the row of the state right after a discontinuity (the
#: row before it, at the same time, holds the left limit), else 0 [-]
RESTART_COLUMN = "restart"


class OutputRows:
    """The solver's output points as the rows every sink gets (``simulate`` and
    ``dnasim run`` alike, so their results.csv are the same).

    ``names``/``units``: ``System.output_names()`` and ``output_units()`` and the
    ``RESTART_COLUMN`` ("-"). ``row(t, y, yp)`` -> the row: ``System.output_row``
    and the restart flag. A time repeated right after a point is the state after
    a restart (flag 1). The point before a time event (a set-point step at a
    tstop) is the left limit: the time functions are evaluated just before the
    event (``math.nextafter``), as the state y is.
    """

    def __init__(self, system, t0: float, t_end: float):
        self.system = system
        self.names = list(system.output_names()) + [RESTART_COLUMN]
        self.units = dict(system.output_units())
        self.units[RESTART_COLUMN] = "-"
        self.time_events = set(system.tstops(t0, t_end))
        self.prev_t: float | None = None

    def restart(self, t: float) -> bool:
        """True when t repeats the previous point's time: the state after a restart."""
        return self.prev_t is not None and float(t) == self.prev_t

    def row(self, t, y, yp):
        import numpy as np

        restart = self.restart(t)
        t_row = math.nextafter(t, -math.inf) if not restart and t in self.time_events else t
        values = self.system.output_row(t_row, y, yp)
        self.prev_t = float(t)
        return np.append(values, float(restart))


class CSVSink:
    """Streams the output rows into a CSV file (``dnasim.run.output.StreamingCSV``):
    header "time [s]", "name [unit]", ...; the file holds whole rows at any time."""

    def __init__(self, path, *, flush_rows: int = 200, flush_seconds: float = 1.0):
        self.path = path
        self.flush_rows, self.flush_seconds = flush_rows, flush_seconds
        self._writer = None

    def open(self, names, units):
        from dnasim.run.output import StreamingCSV, column_header

        header = [column_header("time", "s")] + [column_header(n, units.get(n)) for n in names]
        self._writer = StreamingCSV(
            self.path, header, flush_rows=self.flush_rows, flush_seconds=self.flush_seconds
        )

    def write(self, t, row):
        self._writer.write_row(np.concatenate(([float(t)], np.asarray(row, dtype=float))))

    def close(self):
        if self._writer is not None:
            self._writer.close()

    @property
    def rows(self) -> int:
        """Whole rows on disk."""
        return self._writer.rows_written if self._writer is not None else 0

    @property
    def last_time(self) -> float | None:
        """t [s] of the last whole row on disk (None: no row)."""
        return self._writer.last_time if self._writer is not None else None
