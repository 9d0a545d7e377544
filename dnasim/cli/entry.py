"""The ``dnasim`` program's entry point: the signal handlers first, then the command line.

SIGTERM and SIGINT (Ctrl-C) are caught before anything heavy is imported (this
module imports only ``gc``, ``os``, ``signal``, ``sys``, ``dnasim.core.blas_threads`` (no numpy)
and ``dnasim.core.interrupts``, which holds the handlers), so that a signal at any time
gives one line on stderr and exit code 1, never a silent -15 or a traceback.

Until a command is ready to be interrupted, a signal is *held*: it is recorded and
delivered by :func:`release`. ``dnasim run`` releases it only after it has removed
the previous run's results from its output directory, so an interrupted start never
leaves an older results.csv behind that looks like the new run's. Every other
command releases at once (in the group callback). After the release a signal
raises :class:`Terminated` (SIGTERM) or ``KeyboardInterrupt`` (SIGINT) where the
program is; the commands turn either into one message.

The handlers also unblock SIGTERM and SIGINT, so a signal sent while the parent
kept them blocked (and so pending before Python started) is delivered here.
"""

from __future__ import annotations

import gc
import os
import signal
import sys

from dnasim.core.blas_threads import single_threaded_environment
from dnasim.core.interrupts import (  # noqa: F401  (re-exported: cli uses entry.*)
    _SIGNALS,
    Terminated,
    _state,
    held,
    install,
    installed,
    release,
    signal_name,
)

EXIT_INTERRUPTED = 1  # the command line's "simulation failed or interrupted"


def _message(what: str) -> str:
    return f"dnasim: interrupted ({what}) before the command had done anything"


def main(argv=None) -> int:
    """Run the ``dnasim`` command line with the signal handlers installed first, and
    one BLAS thread unless the user set a number (before numpy is imported:
    ``dnasim.core.blas_threads``)."""
    single_threaded_environment()
    install()
    # Young-generation collections every 10000 new container objects instead of 700:
    # importing numpy, scipy and numba creates ~10^5 objects that all survive, and each
    # collection walks the survivors again (a small plant's run: 0.08 -> 0.05 s CPU in
    # the collector; benchmarks/startup_phases.py)
    gc.set_threshold(10000, 10, 10)
    try:
        import click

        from dnasim.cli.commands import main as cli

        try:
            code = cli.main(args=argv, prog_name="dnasim", standalone_mode=False)
        except click.exceptions.Abort as exc:  # a signal while click parsed the options
            print(_message(signal_name(exc.__cause__)), file=sys.stderr)
            return EXIT_INTERRUPTED
        except click.ClickException as exc:
            exc.show()
            return exc.exit_code
        if _state["pending"] is not None:  # held to the end (--help, --version)
            print(_message(signal_name(_state["pending"])), file=sys.stderr)
            return EXIT_INTERRUPTED
        return code if isinstance(code, int) else 0
    except KeyboardInterrupt as exc:  # before the command line was imported
        print(_message(signal_name(exc)), file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # output piped into a reader that went away (head)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_INTERRUPTED
    finally:
        # exiting now: a late signal must not turn the exit into a traceback
        for s in _SIGNALS:
            signal.signal(s, signal.SIG_IGN)
        # The objects alive now die with the process: moved out of the garbage
        # collector's reach, the interpreter's shutdown does not walk and free them
        # one by one (numba's ~10^5 objects: 0.3 s CPU; benchmarks/startup_phases.py).
        gc.freeze()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
