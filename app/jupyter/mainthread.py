"""Run widget callbacks on the kernel's main thread, whatever thread delivers them.

JupyterLab 4.4+ sends widget messages over kernel *subshells* by default ("comms over
subshells"), and ipykernel 7 runs each subshell on its own thread: a button's handler then runs
beside the main thread, where pyvista's trame server renders the 3D view.  Two threads drawing
with VTK crash the software OpenGL driver (a black view, then a dead kernel).  So every widget
callback Ramure registers goes through :func:`on_main`: called on the main thread it runs at
once (code in a cell, comms without subshells, tests); called on another thread inside a
kernel it is queued on the main thread's event loop (the kernel's ``io_loop``) and runs there
in arrival order as soon as the main thread is free.  Outside a kernel there is no loop to
queue on and no front end to protect: the callback runs where it was called.

>>> calls = []
>>> on_main(calls.append, 1)  # on the main thread: at once
>>> calls
[1]
"""

from __future__ import annotations

import functools
import threading
import traceback
from collections.abc import Callable
from typing import Any


def kernel_loop() -> Any:
    """The tornado IOLoop of the running ipykernel's main thread, or None outside a kernel."""
    from IPython import get_ipython  # ipywidgets depends on IPython

    shell = get_ipython()
    kernel = getattr(shell, "kernel", None) if shell is not None else None
    return getattr(kernel, "io_loop", None)


def is_main_thread() -> bool:
    """Whether the caller runs in the Python main thread (the kernel's, where widgets may be changed)."""
    return threading.current_thread() is threading.main_thread()


def on_main(fn: Callable, *args: Any, **kwargs: Any) -> None:
    """Run ``fn(*args, **kwargs)`` on the main thread: now if we are on it (or outside a kernel),
    else queued on the kernel's main loop.  Returns nothing (a queued call has no result yet)."""
    loop = None if is_main_thread() else kernel_loop()
    if loop is None:
        fn(*args, **kwargs)
        return
    loop.add_callback(functools.partial(_report_errors, fn, *args, **kwargs))


def _report_errors(fn, *args, **kwargs) -> None:
    """A queued call's exception is printed on the kernel's stderr (the log), never lost silently."""
    try:
        fn(*args, **kwargs)
    except Exception:  # noqa: BLE001 - the main loop must survive a failing callback
        traceback.print_exc()


def main_thread_callback(fn: Callable) -> Callable:
    """``fn`` wrapped so that each call goes through :func:`on_main` (for widget observers)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs) -> None:
        on_main(fn, *args, **kwargs)

    return wrapper
