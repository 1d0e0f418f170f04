"""``njit`` for Ramure's compiled kernels: numba's, with its on-disk cache loaded lightly.

Every kernel (``ramure.lsys.ROOM._*_kernel``, ``ramure.gmap.ROOM._*_kernel``) is decorated with
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
arrays use), so a second run of the desktop on Honda n = 17 peaks about 35 MB lower.  A
kernel that is not cached yet (or whose cache is stale) compiles as usual: numba's compiler
refreshes everything itself before compiling.  Other numba functions in the process are not
touched.  numba's runtime module itself, which numba compiles in every process, is loaded
from cached machine code as well (:func:`initialize_runtime`: about 20 MB less).

:func:`on_first_compile` lets a front end say "compiling, first run only" when it happens.
"""

from __future__ import annotations

import contextlib
import errno
import os
import pathlib
import types
from collections.abc import Callable
from typing import Any

__all__ = ["initialize_runtime", "njit", "on_first_compile"]


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
    if isinstance(cache, Cache) and hasattr(cache, "_load_overload"):
        cache.load_overload = types.MethodType(_load_overload, cache)  # type: ignore[method-assign]  # this instance only
    if isinstance(cache, Cache) and hasattr(cache, "_save_overload") and hasattr(cache, "_cache_file"):
        cache.save_overload = types.MethodType(_save_overload, cache)  # type: ignore[method-assign]  # this instance only
    return dispatcher


def _load_overload(cache: Any, sig: Any, target_context: Any) -> Any:
    """Cached machine code for ``sig``, or None (then numba compiles, refreshing its compiler).

    A cache file that cannot be read back (``pickle`` refuses it: a damaged file) counts as
    no cache: the kernel compiles and :func:`_save_overload` writes the file anew, where
    numba's own loader would raise.

    The runtime (NRT) must be up: the cached code calls its allocation and reference
    counting (:func:`initialize_runtime`)."""
    initialize_runtime(target_context)
    try:
        return cache._load_overload(sig, target_context)
    except OSError as exc:  # as numba's own loader: on Windows, another process may hold the file
        if os.name == "nt" and exc.errno == errno.EACCES:
            return None  # numba then compiles
        raise
    except Exception:  # noqa: BLE001 - a damaged cache file (cut short, or its index out of step
        return None  # with it after the source changed under a running process): compile anew


def _save_overload(cache: Any, sig: Any, data: Any) -> None:
    """numba's ``save_overload``, mending a damaged index: numba's own raises when the kernel's
    index file cannot be read back (cut short, or rewritten under a running process), so the
    computation failed after compiling.  Here the index is written anew (the other entries are
    lost: they compile again once) and the save tried once more; if that fails too, the kernel
    runs uncached."""
    try:
        cache._save_overload(sig, data)
        return
    except OSError:
        pass  # as numba's own guard: an unwritable folder is no reason to fail
    except Exception:  # noqa: BLE001 - a damaged index: start it again
        with contextlib.suppress(OSError):
            os.unlink(cache._cache_file._index_path)
    with contextlib.suppress(Exception):
        cache._save_overload(sig, data)


def initialize_runtime(target_context: Any) -> None:
    """numba's ``rtsys.initialize``, with its runtime module loaded as cached machine code.

    Every process that runs a compiled kernel needs numba's runtime: C helpers registered with
    the JIT linker, and a small LLVM module (atomic reference counts) that numba compiles anew
    in each process, through LLVM's optimiser and code generator (about 28 MB of
    ``libllvmlite`` pages touched, 0.05 s).  Here that module is compiled once and its machine
    code kept next to the kernels' caches (the folder numba picks for this file: its
    ``__pycache__``, numba's per-user folder, or ``NUMBA_CACHE_DIR``), in a file named by
    numba's and llvmlite's versions and the CPU, as numba's own cache files are; later
    processes load it (about 9 MB).  Any failure falls back to numba's own initialisation."""
    from numba.core.runtime import rtsys

    if not (hasattr(rtsys, "_init") and hasattr(type(rtsys), "library")):  # another numba: its own way
        rtsys.initialize(target_context)
        return
    if rtsys._init:
        return
    try:
        _runtime_from_cache(rtsys, target_context)
    except Exception:  # numba's internals changed, or a cache that does not link: numba's own way
        rtsys.initialize(target_context)


def _runtime_anchor() -> None:
    """Names this file to numba's cache locator (where the runtime's machine code is kept)."""


def _runtime_file() -> pathlib.Path:
    import hashlib
    import sys

    import llvmlite
    import llvmlite.binding as ll
    import numba
    from numba.core import caching, config

    key = repr(
        (
            numba.__version__,
            llvmlite.__version__,
            sys.version_info[:2],
            ll.get_process_triple(),
            ll.get_host_cpu_name(),
            ll.get_host_cpu_features().flatten(),
            getattr(config, "CPU_NAME", None),
            getattr(config, "CPU_FEATURES", None),
            getattr(config, "OPT", None),
        )
    )
    folder = caching.FunctionCache(_runtime_anchor).cache_path
    return pathlib.Path(folder) / f"numba_runtime-{hashlib.sha256(key.encode()).hexdigest()[:20]}.bin"


def _runtime_from_cache(rtsys: Any, target_context: Any) -> None:
    """What ``rtsys.initialize`` does, with the runtime module's machine code read from
    :func:`_runtime_file` (or compiled with object caching on, and written there)."""
    import pickle

    import llvmlite.binding as ll
    from numba.core import config
    from numba.core.compiler_lock import global_compiler_lock
    from numba.core.runtime import _nrt_python, nrtdynmod  # type: ignore[attr-defined]  # numba's C extension

    from ramure.errors import RamureError
    from ramure.io import write_bytes

    with global_compiler_lock:
        if getattr(config, "NRT_STATS", False):
            _nrt_python.memsys_enable_stats()
        for name, address in _nrt_python.c_helpers.items():
            ll.add_symbol(name if name.startswith("_") else "NRT_" + name, address)
        path = _runtime_file()
        codegen = target_context.codegen()
        try:
            library = codegen.unserialize_library(pickle.loads(path.read_bytes()))
        except (OSError, EOFError, pickle.UnpicklingError, ValueError, TypeError):
            ir_module, library = nrtdynmod.create_nrt_module(target_context)
            library.enable_object_caching()
            library.add_ir_module(ir_module)
            library.finalize()
            try:
                write_bytes(path, pickle.dumps(library.serialize_using_object_code()))
            except RamureError:
                pass  # a read-only folder: compiled again next time, as numba would
        library.get_pointer_to_function("nrt_unresolved_abort")  # linked now, not in a kernel
        rtsys._library = library
        rtsys._init = True


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
