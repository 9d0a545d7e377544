"""dnasim's numba kernels, loaded or compiled one group at a time, and said so when compiled.

A *group* is the compiled entry points one kind of property call needs (IF97 ``state``,
``states``, the memo loop of the pipes, ``h_pT``, the saturation line, the transport
kernel), registered by the medium that calls them (:func:`register`). The first call
of a kind in a process runs :func:`ensure`, which

* installs the lean cache loads of :mod:`dnasim.media.numba_loading`;
* asks numba's cache whether each of the group's entry points has a compiled version
  for this source and this CPU (its index file; numba's own check, ``_load_index``);
* if one has not, writes one line on stderr, once per process::

      dnasim: compiling the IF97 kernels once (about 6 to 9 s CPU, by what the plant
      uses); later runs use the cache in /path/to/cache

  (the range: the group compiled now together with the shared code, up to every group
  not yet cached), then compiles;
* runs the group's warm-up call with SIGTERM/SIGINT held (``dnasim.core.interrupts.held``):
  a signal raised inside numba's compiler callbacks would be swallowed there.

So a run compiles (first use on a machine, or after a change of the sources) only the
groups it calls: an air plant nothing, a plant of a few water nodes the ``state`` group,
a plant with pipes also the memo loop (``benchmarks/cold_start.py`` measures it).
numba's cache is ``__pycache__`` beside the sources, or ``NUMBA_CACHE_DIR`` when set, or
a per-user directory when the package directory is not writable (numba's rule); the
line names the directory numba uses.

When numba's internals differ from those read here (no ``_cache._cache_file``), the
groups are loaded as before and nothing is printed.
"""

from __future__ import annotations

import sys
from collections.abc import Callable

__all__ = ["ensure", "register", "uncached", "cache_directory"]


class _Group:
    __slots__ = ("dispatchers", "warm_up", "cpu_s", "label")

    def __init__(self, dispatchers, warm_up, cpu_s, label):
        self.dispatchers = dispatchers
        self.warm_up = warm_up
        self.cpu_s = cpu_s
        self.label = label


_GROUPS: dict[str, _Group] = {}
_READY: set[str] = set()
_ANNOUNCED: set[str] = set()  # labels announced in this process

#: [s] CPU of compiling the code the IF97 groups share (the Gibbs functions, backward
#: equations and solvers), paid by the first IF97 group compiled in a process
#: (measured with an empty NUMBA_CACHE_DIR on the 2-core development machine)
SHARED_CPU_S = {"IF97": 6.0}


def register(
    name: str,
    dispatchers: tuple,
    warm_up: Callable[[], object],
    cpu_s: float,
    label: str = "IF97",
) -> None:
    """Register group ``name``: its numba dispatchers, a call that compiles or loads
    them all, and the CPU seconds its own compile costs beyond the shared code."""
    _GROUPS[name] = _Group(tuple(dispatchers), warm_up, float(cpu_s), label)


def _is_cached(disp) -> bool | None:
    """True when numba's cache holds a version of dispatcher ``disp`` for its current
    source and this CPU, False when not, None when it cannot tell."""
    try:
        cache = disp._cache
        index = cache._cache_file._load_index()  # {} when absent or of another source
        codegen = disp.targetctx.codegen()
        # a key is (signature, CPU, hashes of the bytecode and closure): numba's own key
        return any(cache._index_key(k[0], codegen) == k for k in index)
    except Exception:  # noqa: BLE001 - another numba: cannot tell, say nothing
        return None


def cache_directory(name: str) -> str | None:
    """The directory numba's cache uses for group ``name`` (None if unknown)."""
    try:
        return str(_GROUPS[name].dispatchers[0]._cache._cache_path)
    except Exception:  # noqa: BLE001
        return None


def uncached(name: str) -> bool:
    """True when some entry point of group ``name`` has no usable cached version."""
    return any(_is_cached(d) is False for d in _GROUPS[name].dispatchers)


def ensure(name: str) -> None:
    """Load (or compile, saying so once per process) the kernels of group ``name``;
    a no-op after the first call (module doc)."""
    if name in _READY:
        return
    from dnasim.core.interrupts import held
    from dnasim.media.numba_loading import install

    install()
    group = _GROUPS[name]
    if group.label not in _ANNOUNCED and uncached(name):
        _announce(name, group)
    with held():
        group.warm_up()
    _READY.add(name)


def _announce(name: str, group: _Group) -> None:
    shared = SHARED_CPU_S.get(group.label, 0.0)
    compiled = {name} | {n for n, g in _GROUPS.items() if g.label == group.label}
    compiled = {n for n in compiled if n not in _READY}
    low = shared + group.cpu_s
    high = shared + sum(_GROUPS[n].cpu_s for n in compiled if n == name or uncached(n))
    span = (
        f"about {low:.0f} s CPU"
        if round(high) <= round(low)
        else (f"about {low:.0f} to {high:.0f} s CPU, by what the plant uses")
    )
    where = cache_directory(name) or "numba's cache directory"
    sys.stderr.write(
        f"dnasim: compiling the {group.label} kernels once ({span}); later runs use the "
        f"cache in {where}\n"
    )
    sys.stderr.flush()
    _ANNOUNCED.add(group.label)
