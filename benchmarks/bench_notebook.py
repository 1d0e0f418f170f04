"""``examples/explore.ipynb`` Run All in a new kernel, cell by cell (issue 34, section 5).

The notebook runs as the notebook test runs it (nbclient, a fresh ``python3`` kernel at the
repository root, the static picture view, an empty variant cache).  ``seconds`` is the wall
time of the whole run, kernel start included; ``cells_seconds`` the sum of the cells' own
times (from each cell's ``execute_input`` to its ``execute_reply``, as nbclient records
them); ``slowest`` the five slowest cells (index, seconds, first line).  The target is
15 s for Run All.

The machine these run on is often shared, so wall times swing with its load; the kernel's own
CPU time does much less.  ``kernel_cpu_seconds`` is the CPU the kernel process used (its
threads included: VTK's software rendering draws on some) from its start to the end of the
last cell, read from ``/proc`` (Linux; None elsewhere); ``slowest_cpu`` the five cells that
used the most.  ``load`` is the one-minute load average when the run ended.
"""

from __future__ import annotations

import datetime
import os
import pathlib
import tempfile
import time
from unittest import mock

ROOT = pathlib.Path(__file__).resolve().parents[1]
TARGET_SECONDS = 15.0


def _cell_seconds(cell) -> float | None:
    timing = cell.get("metadata", {}).get("execution", {})
    start, end = timing.get("iopub.execute_input"), timing.get("shell.execute_reply")
    if not (start and end):
        return None
    parse = datetime.datetime.fromisoformat
    return (parse(end.replace("Z", "+00:00")) - parse(start.replace("Z", "+00:00"))).total_seconds()


def _cpu_seconds(pid: int) -> float | None:
    """User + system CPU seconds of process ``pid`` (all its threads), or None off Linux."""
    try:
        fields = pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


class _KernelClock:
    """The kernel's CPU seconds before and after each cell (nbclient's cell hooks)."""

    def __init__(self) -> None:
        self.client = None
        self.before: dict[int, float | None] = {}
        self.cells: dict[int, float] = {}
        self.total: float | None = None

    def _now(self) -> float | None:
        process = getattr(getattr(self.client.km, "provisioner", None), "process", None)
        return None if process is None else _cpu_seconds(process.pid)

    def start(self, cell, cell_index, **_) -> None:
        self.before[cell_index] = self._now()

    def end(self, cell, cell_index, **_) -> None:
        now, then = self._now(), self.before.get(cell_index)
        if now is not None and then is not None:
            self.cells[cell_index], self.total = now - then, now


def bench_explore_notebook():
    import nbclient
    import nbformat

    nb = nbformat.read(ROOT / "examples" / "explore.ipynb", as_version=4)
    with tempfile.TemporaryDirectory() as cache:
        env = {"PYVISTA_JUPYTER_BACKEND": "static", "RAMURE_CACHE": cache}
        with mock.patch.dict(os.environ, env):  # the kernel inherits them; restored after
            t0 = time.perf_counter()
            clock = _KernelClock()
            client = clock.client = nbclient.NotebookClient(
                nb,
                kernel_name="python3",
                timeout=600,
                record_timing=True,
                resources={"metadata": {"path": str(ROOT)}},
                on_cell_execute=clock.start,
                on_cell_executed=clock.end,
            )
            client.execute()
            total = time.perf_counter() - t0
    cells = [
        (i, _cell_seconds(cell), (cell.source.splitlines() or [""])[0][:60])
        for i, cell in enumerate(nb.cells)
        if cell.cell_type == "code"
    ]
    timed = [(i, s, line) for i, s, line in cells if s is not None]
    errors = sum(o.output_type == "error" for cell in nb.cells if cell.cell_type == "code" for o in cell.outputs)
    slowest = sorted(timed, key=lambda c: -c[1])[:5]
    return {
        "seconds": round(total, 2),
        "cells_seconds": round(sum(s for _, s, _ in timed), 2),
        "code_cells": len(cells),
        "slowest": [[i, round(s, 2), line] for i, s, line in slowest],
        "kernel_cpu_seconds": None if clock.total is None else round(clock.total, 2),
        "slowest_cpu": [[i, round(s, 2)] for i, s in sorted(clock.cells.items(), key=lambda c: -c[1])[:5]],
        "load": round(os.getloadavg()[0], 1),
        "errors": errors,
        "target_seconds": TARGET_SECONDS,
        "ok": errors == 0 and total <= TARGET_SECONDS,
    }
