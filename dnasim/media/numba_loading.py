"""Loading numba's cached kernels without numba's compiler set-up.

Before every load of a kernel from its on-disk cache (``cache=True``), numba
"refreshes" its CPU target context: it imports and installs the typing and lowering
registries of everything it can compile (numba.np.arraymath, linalg, random, the typed
containers, ...). In a fresh process that is 0.1 to 0.2 s of CPU before the first
cached kernel runs, although a cached kernel is machine code that needs only the
runtime (NRT) symbols it links against.

:func:`install` replaces the context's ``refresh`` (the instance attribute shadows
the method) by one that, when called directly by the cache loader
(``numba.core.caching.Cache.load_overload``), only initialises the runtime
(``rtsys.initialize``, numba's own call, idempotent), and otherwise does numba's full
refresh. So a kernel that is not in the cache (first use on a machine, changed source)
is compiled exactly as before: the compiler refreshes the context itself
(``CompilerBase.__init__``) and gets every registry. Loaded kernels are the same
machine code either way (the IF97 tests and the example plants' results are
bit-identical).

The replacement is installed once per process, by the first dnasim code that loads
compiled kernels (``dnasim.media.if97``), and serves every later cached load in the
process (other dnasim kernels, the user's). With a numba whose internals differ from
these (no ``Cache.load_overload``, no ``rtsys``) nothing is installed and numba
behaves as it always does.
"""

from __future__ import annotations

import sys

__all__ = ["install", "installed"]

_state = {"installed": False}


def installed() -> bool:
    """True when the lean cache loads are installed in this process."""
    return _state["installed"]


def install() -> bool:
    """Make numba's cache loads skip the compiler set-up (module doc); idempotent.
    Returns whether they are installed (False with an incompatible numba). Imports
    numba."""
    if _state["installed"]:
        return True
    try:
        from numba.core.caching import Cache
        from numba.core.registry import cpu_target
        from numba.core.runtime import rtsys

        ctx = cpu_target.target_context
        loader = Cache.load_overload.__code__
        full = type(ctx).refresh
    except (ImportError, AttributeError):  # pragma: no cover - another numba
        return False

    def refresh():
        if sys._getframe(1).f_code is loader:
            rtsys.initialize(ctx)  # what the loaded machine code links against
        else:
            full(ctx)

    ctx.refresh = refresh
    _state["installed"] = True
    return True
