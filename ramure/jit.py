"""``njit`` for Ramure's compiled kernels: numba's, with its on-disk cache loaded lightly.

Every kernel (``ramure.lsys._*_kernel``, ``ramure.gmap._*_kernel``) is decorated with
``@njit(cache=True, ...)`` from here.  The first run after an install compiles each kernel
once (LLVM; 15-25 s for all of them) and numba saves the machine code next to the module
(``__pycache__/*.nbi`` index and ``*.nbc`` code, written to a temporary name then renamed, so
parallel processes do not corrupt it).  Where that folder is not writable (a wheel in a
read-only site-packages) numba uses its own per-user cache folder instead
(``~/.cache/numba``), and ``NUMBA_CACHE_DIR`` overrides both.  Nothing is written anywhere
else.

Loading cached code still costs something in numba as it ships: before each load it
"refreshes" its compiler, which imports every implementation registry (NumPy, linear algebra
through ``scipy.linalg``, typed containers, random...) and the typing declarations, about
50 MB and 0.8 s in a fresh process, none of which a cached kernel needs.  Here the caches
of Ramure's kernels load with only numba's runtime initialised (the reference counting its
arrays use), so a second run of the desktop on Honda n = 17 peaks about 50 MB lower.  A
kernel that is not cached yet (or whose cache is stale) compiles as usual: numba's compiler
refreshes everything itself before compiling.  Other numba functions in the process are not
touched.

:func:`on_first_compile` lets a front end say "compiling, first run only" when it happens.
"""

from __future__ import annotations

import types
from collections.abc import Callable
from typing import Any

__all__ = ["njit", "on_first_compile"]


def njit(*args: Any, **options: Any) -> Any:
    """``numba.njit`` (same arguments), with the light cache loading described above when
    ``cache=True``.  Usable bare (``@njit``), with options (``@njit(cache=True)``) or with
    signatures (compiled, or loaded from the cache, when decorating, as numba does)."""
    import numba

    if len(args) == 1 and callable(args[0]) and not options:  # bare @njit
        return _load_lightly(numba.njit(args[0]))
    decorator = numba.njit(*args, **options)
    return lambda f: _load_lightly(decorator(f))


def _load_lightly(dispatcher: Any) -> Any:
    """Replace the dispatcher's cache loader (numba's ``Cache.load_overload``, which refreshes
    the whole compiler first) by one that initialises only numba's runtime.  Left as it is when
    numba's cache does not have the expected shape (another numba version)."""
    from numba.core.caching import Cache

    cache = getattr(dispatcher, "_cache", None)
    if isinstance(cache, Cache) and hasattr(cache, "_load_overload") and hasattr(cache, "_guard_against_spurious_io_errors"):
        cache.load_overload = types.MethodType(_load_overload, cache)  # type: ignore[method-assign]  # this instance only
    return dispatcher


def _load_overload(cache: Any, sig: Any, target_context: Any) -> Any:
    """Cached machine code for ``sig``, or None (then numba compiles, refreshing its compiler).

    The runtime (NRT) must be up: the cached code calls its allocation and reference
    counting, which ``rtsys.initialize`` compiles and registers with the JIT linker."""
    from numba.core.runtime import rtsys

    rtsys.initialize(target_context)
    with cache._guard_against_spurious_io_errors():
        return cache._load_overload(sig, target_context)
    return None  # the guard swallowed an I/O error: numba then compiles


def on_first_compile(callback: Callable[[str], None]) -> None:
    """Call ``callback(name)`` once, when numba starts compiling a function in this process
    (a kernel with no usable cache: the first run after an install or an upgrade).  Uses
    numba's event API (``numba:compile``); cached loads do not fire it."""
    from numba.core import event

    class _Once(event.Listener):
        done = False

        def on_start(self, ev: event.Event) -> None:
            if not self.done:
                self.done = True
                dispatcher = (ev.data or {}).get("dispatcher")
                callback(getattr(getattr(dispatcher, "py_func", None), "__qualname__", "a kernel"))

        def on_end(self, ev: event.Event) -> None:
            pass

    event.register("numba:compile", _Once())
