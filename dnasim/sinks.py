"""Output sinks: where ``simulate`` streams the output rows while the solver runs.

Contract: ``open(names, units)`` once before the first row (names in
``System.output_names()`` order, units name -> unit string), ``write(t, row)``
per output point (t [s], row: ndarray in names order), ``close()`` once at the
end, also after a failure.
"""

from __future__ import annotations

import numpy as np

__all__ = ["CSVSink"]


class CSVSink:
    """Streams the output rows into a CSV file (``dnasim.output.StreamingCSV``):
    header "time [s]", "name [unit]", ...; the file holds whole rows at any time."""

    def __init__(self, path, *, flush_rows: int = 200, flush_seconds: float = 1.0):
        self.path = path
        self.flush_rows, self.flush_seconds = flush_rows, flush_seconds
        self._writer = None

    def open(self, names, units):
        from dnasim.output import StreamingCSV, column_header

        header = [column_header("time", "s")] + [column_header(n, units.get(n)) for n in names]
        self._writer = StreamingCSV(
            self.path, header, flush_rows=self.flush_rows, flush_seconds=self.flush_seconds
        )

    def write(self, t, row):
        self._writer.write_row(np.concatenate(([float(t)], np.asarray(row, dtype=float))))

    def close(self):
        if self._writer is not None:
            self._writer.close()
