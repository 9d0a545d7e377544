"""SIGTERM and SIGINT held and released: the signal handlers of the ``dnasim`` program.

``dnasim.cli.entry`` installs them before anything heavy is imported (:func:`install`).
Until a command is ready to be interrupted, a signal is *held*: it is recorded and
delivered by :func:`release`. After the release a signal raises :class:`Terminated`
(SIGTERM) or ``KeyboardInterrupt`` (SIGINT) where the program is. Code that must
not be interrupted by an exception (numba's compiler callbacks in
``dnasim.media.if97``, the atomic writes of ``dnasim.run.output``) runs inside
:func:`held`.

This module imports only ``contextlib`` and ``signal``, and nothing of dnasim, so that
every stage may use it (it sits in the first stage of docs/architecture.md).
"""

from __future__ import annotations

import contextlib
import signal

_SIGNALS = (signal.SIGTERM, signal.SIGINT)
_state = {"holding": False, "pending": None, "installed": False}


class Terminated(KeyboardInterrupt):
    """Raised for SIGTERM, so that a run stops as on Ctrl-C (the solver hands over
    what it computed, as for KeyboardInterrupt)."""


def signal_name(exc: BaseException | int | None) -> str:
    """ "SIGTERM" or "Ctrl-C" for an exception or a signal number."""
    if isinstance(exc, Terminated) or exc == signal.SIGTERM:
        return "SIGTERM"
    return "Ctrl-C"


def _handler(signum, frame):
    if _state["holding"]:
        if _state["pending"] is None:
            _state["pending"] = signum
        return
    _raise(signum)


def _raise(signum):
    if signum == signal.SIGTERM:
        raise Terminated()
    raise KeyboardInterrupt()


def install() -> None:
    """Catch SIGTERM and SIGINT from now on and hold them until :func:`release`
    (a second call keeps a signal already held)."""
    if _state["installed"]:
        return
    _state.update(holding=True, pending=None, installed=True)
    for s in _SIGNALS:
        signal.signal(s, _handler)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, _SIGNALS)


def installed() -> bool:
    """True when this process was started through :func:`main` (the handlers are ours)."""
    return _state["installed"] and signal.getsignal(signal.SIGTERM) is _handler


def release() -> None:
    """Stop holding signals; raise for one that arrived while they were held."""
    if not _state["holding"]:
        return
    _state["holding"] = False
    pending, _state["pending"] = _state["pending"], None
    if pending is not None:
        _raise(pending)


@contextlib.contextmanager
def held():
    """Hold SIGTERM/SIGINT for the duration (code that must not be interrupted by an
    exception, e.g. numba's compiler callbacks); a signal that arrived meanwhile is
    raised at the end. Does nothing when the handlers are not ours or already hold."""
    if not installed() or _state["holding"]:
        yield
        return
    _state["holding"] = True
    try:
        yield
    finally:
        release()
