"""A guard against a reference-counting bug of PySide6 6.12 on CPython 3.11.

In that combination every Qt method that returns nothing (``setText``,
``update``, ``processEvents``...) hands Python ``None`` without taking a
reference to it.  CPython 3.12+ does not count references to ``None`` (it is
immortal), but 3.11 does: each call takes one away, and after some 20,000
calls the interpreter aborts with "none_dealloc: deallocating None" -- a few
minutes of normal use of the window.

:func:`protect_none` measures the leak with a harmless call; only if it is
there does it add a very large number to ``None``'s reference count, so the
count can never reach zero in a session.  On Python 3.12+ or a fixed PySide6
it does nothing.  (The real fix is a PySide6 release without the bug, or
Python 3.12+.)
"""

from __future__ import annotations

import ctypes
import sys
from collections.abc import Callable

RESERVE = 1 << 40
_PROTECTED = False


def none_leak_per_call(calls: int = 200) -> float:
    """How many references to ``None`` one void Qt call loses (0 when the bindings are sound)."""
    from PySide6.QtCore import QObject

    probe = QObject()
    before = sys.getrefcount(None)
    for _ in range(calls):
        probe.setObjectName("probe")
    return max(0.0, (before - sys.getrefcount(None)) / calls)


def protect_none() -> bool:
    """Make ``None`` unkillable if the Qt bindings leak references to it; returns True if applied."""
    global _PROTECTED
    if _PROTECTED or sys.version_info >= (3, 12) or sys.implementation.name != "cpython":
        return _PROTECTED
    if none_leak_per_call() < 0.5:
        return False
    ctypes.c_ssize_t.from_address(id(None)).value += RESERVE
    _PROTECTED = True
    return True


def skip_source_scan() -> bool:
    """Stop PySide6 from keeping the source of every module imported after it (about 50 MB).

    Importing PySide6 (``shiboken6``) replaces ``__import__``: each module imported afterwards is
    asked whether it uses PySide6 (for ``from __feature__ import snake_case``) by
    ``inspect.getsource(module)``, and ``linecache`` then keeps that source, split into lines,
    for the life of the process: pyvista, VTK's wrappers, matplotlib, numba... 500-760 files and
    about 50 MB of the desktop's resident memory (Honda n = 17: 733 -> 679 MB at the first
    frame).  The same test ("PySide6" in the module's source) is made here by reading the
    module's ``.py`` file once, without caching it; a module without one (an extension, a
    zipped module) gets PySide6's own test.  Called when the desktop package is imported;
    returns True if applied (False without PySide6, or a PySide6 whose feature module has
    another shape)."""
    global _PYSIDE_TEST
    try:
        import PySide6  # noqa: F401  (installs the import hook and its feature module, not Qt's libraries)
    except ImportError:
        return False
    feature = sys.modules.get("shibokensupport.feature")
    test = getattr(feature, "_mod_uses_pyside", None)
    if feature is None or not callable(test):
        return False
    if test is not _mentions_pyside:
        _PYSIDE_TEST = test
        feature._mod_uses_pyside = _mentions_pyside  # type: ignore[attr-defined]  # PySide6's module, replaced here
    return True


_PYSIDE_TEST: Callable[[object], bool] | None = None  # PySide6's own test, for modules without a .py file


def _mentions_pyside(module: object) -> bool:
    """Whether ``module``'s source contains "PySide6" (its file read, not kept)."""
    path = getattr(module, "__file__", None)
    if isinstance(path, str) and path.endswith(".py"):
        try:
            with open(path, "rb") as source:
                return b"PySide6" in source.read()
        except OSError:
            pass
    return bool(_PYSIDE_TEST(module)) if _PYSIDE_TEST is not None else False
