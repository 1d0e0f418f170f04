"""``examples/explore.ipynb`` Run All in a new kernel, cell by cell (issue 34, section 5).

The notebook runs as the notebook test runs it (nbclient, a fresh ``python3`` kernel at the
repository root, the static picture view, an empty variant cache).  ``seconds`` is the wall
time of the whole run, kernel start included; ``cells_seconds`` the sum of the cells' own
times (from each cell's ``execute_input`` to its ``execute_reply``, as nbclient records
them); ``slowest`` the five slowest cells (index, seconds, first line).  The target is
15 s for Run All; nothing here is optimised yet.
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


def bench_explore_notebook():
    import nbclient
    import nbformat

    nb = nbformat.read(ROOT / "examples" / "explore.ipynb", as_version=4)
    with tempfile.TemporaryDirectory() as cache:
        env = {"PYVISTA_JUPYTER_BACKEND": "static", "RAMURE_CACHE": cache}
        with mock.patch.dict(os.environ, env):  # the kernel inherits them; restored after
            t0 = time.perf_counter()
            client = nbclient.NotebookClient(
                nb, kernel_name="python3", timeout=600, record_timing=True, resources={"metadata": {"path": str(ROOT)}}
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
        "errors": errors,
        "target_seconds": TARGET_SECONDS,
        "ok": errors == 0 and total <= TARGET_SECONDS,
    }
