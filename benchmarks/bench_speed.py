"""Million-module plants (issue 14): turtle, context matching, grammar to pixels, edits, memory.

Each benchmark reports modules/s where it applies and the process's peak RSS
(``peak_mb``, Linux ``ru_maxrss``: the whole process so far, numba and VTK
included).  Ratios compare with Ramure 0.1's code run in the same process: the
original Python turtle and context matcher kept as references in
``tests/lsys/`` (loaded from there).  The machine is shared: figures are
medians of a few runs; rendering is off-screen (software OpenGL under Xvfb
when no GPU), so run under ``xvfb-run -a``.
"""

from __future__ import annotations

import importlib.util
import pathlib
import resource
import statistics
import time

import numpy as np
from benchtools import child_json

from ramure.lsys import LSystem

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _peak_mb():
    return round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)


def _load(name):
    """A module from tests/lsys (the slow references), loaded by path."""
    import sys

    for folder in (str(ROOT), str(ROOT / "tests" / "lsys")):  # the root: ``tests.hardening`` imports
        if folder not in sys.path:
            sys.path.insert(0, folder)
    spec = importlib.util.spec_from_file_location(name, ROOT / "tests" / "lsys" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _median(fn, repeat=5):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def _median_wall_cpu(fn, repeat=5):
    """Median wall and CPU (this process) seconds of ``fn()``: on a loaded machine the CPU time
    is what the code costs, the wall time what it costs there and then."""
    wall, cpu, out = [], [], None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return statistics.median(wall), statistics.median(cpu), out


def bench_turtle_honda_n17():
    """The compiled turtle on Honda sympodial n=17 (1.44 M modules): >= 10 M modules/s."""
    from ramure.lsys.interpretation.turtle import interpret

    d = LSystem.from_file("honda_sympodial").derive(n=17)
    interpret(d)  # loads numba and the cached kernel
    seconds, sk = _median(lambda: interpret(d))
    reference = _load("turtle_reference")
    t0 = time.perf_counter()
    reference.interpret(d)
    old = time.perf_counter() - t0
    rate = len(d) / seconds
    return _plain(
        {
            "seconds": round(seconds, 4),
            "modules": len(d),
            "segments": len(sk),
            "modules_per_second": int(rate),
            "target_modules_per_second": 10_000_000,
            "old_seconds": round(old, 3),
            "speedup": round(old / seconds, 1),
            "peak_mb": _peak_mb(),
            "ok": rate >= 10_000_000,
        }
    )


def bench_context_plant_n50():
    """Context-sensitive derivation, context_plant n=50 (837k modules): target >= 3 M modules/s.

    ``previous_*``: the code before the one-block assembly (per-rule tree appends, groups
    matched one by one; kept in tests/lsys/test_lsys_derive_assemble.py), alternated with
    the new code in the same run.  The old matcher (one module at a time) is timed at n=42,
    where it still takes seconds.
    """
    ls = LSystem.from_file("context_plant")
    ls.derive(n=30)
    previous = _load("test_lsys_derive_assemble").ReferenceAssembly(ls.grammar)  # per-rule appends, per group
    previous.derive(n=30)
    walls, cpus, prev_walls, prev_cpus = [], [], [], []
    for _ in range(5):  # alternated, so both see the same load
        wall, cpu, d = _median_wall_cpu(lambda: ls.derive(n=50), repeat=1)
        walls.append(wall)
        cpus.append(cpu)
        wall, cpu, _ = _median_wall_cpu(lambda: previous.derive(n=50), repeat=1)
        prev_walls.append(wall)
        prev_cpus.append(cpu)
    seconds, cpu = statistics.median(walls), statistics.median(cpus)
    rate = len(d) / seconds
    reference = _load("test_lsys_context").ReferenceLSystem(ls.grammar)
    new42, _ = _median(lambda: ls.derive(n=42), repeat=3)
    t0 = time.perf_counter()
    small = reference.derive(n=42)
    old42 = time.perf_counter() - t0
    return _plain(
        {
            "seconds": round(seconds, 3),
            "modules": len(d),
            "modules_per_second": int(rate),
            "cpu_seconds": round(cpu, 3),
            "modules_per_cpu_second": int(len(d) / cpu),
            "previous_seconds": round(statistics.median(prev_walls), 3),
            "previous_cpu_seconds": round(statistics.median(prev_cpus), 3),
            "speedup_vs_previous": round(statistics.median(np.divide(prev_walls, walls)), 2),
            "target_modules_per_second": 3_000_000,
            "n42_modules": len(small),
            "n42_seconds": round(new42, 3),
            "n42_old_seconds": round(old42, 3),
            "n42_speedup": round(old42 / new42, 1),
            "peak_mb": _peak_mb(),
            "ok": rate >= 3_000_000,
        }
    )


def bench_context_20000_siblings():
    """``w: [A]`` x 20000 with ``A < A > A -> B`` (69 s with the old matcher): <= 0.5 s."""
    ls = LSystem.from_text("n: 1\nw: " + "[A]" * 20000 + "\np:\n  A < A > A -> B\n  A < A -> C\n")
    ls.derive()
    seconds, d = _median(lambda: ls.derive(), repeat=5)
    chained = LSystem.from_text("n: 1\nw: " + "A[A]" * 20000 + "\np:\n  A < A > A -> B\n")
    chain_seconds, c = _median(lambda: chained.derive(), repeat=3)
    return _plain(
        {
            "seconds": round(seconds, 4),
            "modules": len(d),
            "modules_per_second": int(len(d) / seconds),
            "chain_seconds": round(chain_seconds, 4),
            "chain_rewritten": c.count("B"),
            "chain_modules_per_second": int(len(c) / chain_seconds),
            "target_seconds": 0.5,
            "peak_mb": _peak_mb(),
            "ok": max(seconds, chain_seconds) <= 0.5,
        }
    )


def _plant_view(size=(1000, 800), native=None):
    """The desktop's 3D view (:class:`~ramure.app.desktop.view.plant_view.PlantView`: its look, plant actors
    with level of detail, hairlines, ground), shown at ``size`` and painted once (an open window).

    The benchmarks draw through it, so they measure what the desktop user gets.  ``native``:
    VTK in a native window (:mod:`ramure.app.desktop.view.native_view`, the default on X11) or
    pyvistaqt's QOpenGLWidget (False; None: as the desktop chooses).
    """
    from ramure.app.desktop.launch import make_application
    from ramure.app.desktop.view.plant_view import PlantView

    from PySide6.QtTest import QTest

    app = make_application()
    view = PlantView(native=native)
    view.resize(*size)
    view.show()
    QTest.qWaitForWindowExposed(view, 10_000)  # a view not yet on screen skips its paints
    for _ in range(10):
        app.processEvents()
    _paint(view)
    return app, view


def _paint(view):
    """Paint ``view`` now (``redraw(now=True)`` renders even when Qt skips the repaint) and wait
    until the frame is on the screen.

    The native view renders and swaps the frame into its X window within ``redraw(now=True)``
    (synchronously); ``WaitForCompletion`` then waits for the (software) GL to finish.  The
    QOpenGLWidget view's frame reaches the screen only when Qt has composed the window
    afterwards, in the event loop: its ``frameSwapped`` signal is waited for (at most 1 s).
    """
    from PySide6.QtWidgets import QApplication

    swapped = []

    def done():
        swapped.append(True)

    if not view.native:
        view.plotter.frameSwapped.connect(done)
    view.redraw(now=True)
    window = view.plotter.ren_win
    window.MakeCurrent()
    window.WaitForCompletion()
    if not view.native:
        deadline = time.perf_counter() + 1.0
        while not swapped and time.perf_counter() < deadline:
            QApplication.processEvents()
        view.plotter.frameSwapped.disconnect(done)


def _show(view, snap, reset_camera=None):
    """What the window does with a new plant version: colours, :meth:`PlantView.show_plant`, a paint."""
    from ramure.app.desktop import state

    view.show_plant(snap, state.cell_colors(snap.mesh, snap.selection, base=state.base_colors(snap.mesh)), reset_camera)
    _paint(view)


def bench_grammar_to_pixels_honda_n17(native=None):
    """Derive + turtle + mesh + first frame in the desktop's 3D view, Honda n=17: <= 1.0 s.

    The view (:func:`_plant_view`) is open and has painted once; ``first_frame`` is
    :meth:`PlantView.show_plant` (colours, actors, camera framed) and the paint, a draft
    for so large a plant (see :mod:`ramure.app.desktop.view.plant_view`); ``polish`` is the
    full-quality repaint that follows when the user pauses, ``polished_seconds`` the
    total with it (the pause itself not counted).

    The mesh is what the explorer shows (:func:`ramure.app.model.mesh_sides`: 3-sided
    tubes at 131k segments); ``sides8_*`` is the same with 8-sided tubes.  ``native``: the
    view's window (see :func:`_plant_view`).
    """
    from types import SimpleNamespace

    from ramure.app.model import mesh_sides
    from ramure.lsys.interpretation.geometry import skeleton_to_polydata

    ls = LSystem.from_file("honda_sympodial")
    app, warm = _plant_view(native=native)
    small = ls.derive(n=4).skeleton()  # numba kernels and shaders loaded
    _show(warm, SimpleNamespace(mesh=skeleton_to_polydata(small), skeleton=small, selection=()), True)
    warm.close()

    def run(sides=None):
        _, view = _plant_view(native=native)  # the window is open, as in the desktop: its first paint is not counted
        t0 = time.perf_counter()
        d = ls.derive(n=17)
        t1 = time.perf_counter()
        sk = d.skeleton()
        t2 = time.perf_counter()
        mesh = skeleton_to_polydata(sk, sides or mesh_sides(len(sk)))
        t3 = time.perf_counter()
        _show(view, SimpleNamespace(mesh=mesh, skeleton=sk, selection=()), True)
        t4 = time.perf_counter()
        view.polish()  # the full-quality frame the polish timer draws once the user pauses
        _paint(view)
        t5 = time.perf_counter()
        image = view.grab_image()
        view.close()
        row = image.height() // 2
        assert len({image.pixel(x, row) for x in range(0, image.width(), 7)}) > 2  # not blank
        return t4 - t0, (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4), len(d), mesh.n_cells

    runs = [run() for _ in range(3)]
    total = statistics.median(r[0] for r in runs)
    parts = np.median([r[1] for r in runs], axis=0)
    full = run(8)
    return _plain(
        {
            "seconds": round(total, 3),
            "window": "native" if warm.native else "QOpenGLWidget",
            "derive": round(parts[0], 3),
            "turtle": round(parts[1], 3),
            "mesh": round(parts[2], 3),
            "first_frame": round(parts[3], 3),
            "polish": round(parts[4], 3),
            "polished_seconds": round(total + parts[4], 3),
            "modules": runs[0][2],
            "cells": runs[0][3],
            "modules_per_second": int(runs[0][2] / total),
            "sides8_seconds": round(full[0], 3),
            "sides8_cells": full[3],
            "target_seconds": 1.0,
            "peak_mb": _peak_mb(),
            "ok": total <= 1.0,
        }
    )


def bench_regrow_and_undo_honda_n17(native=None):
    """Regrow 10 leaves on Honda n=17 to the redrawn frame (<= 100 ms); undo (<= 50 ms).

    Drawn as the desktop draws (:func:`_plant_view`, 1000x800): ``regen_seconds`` is the
    session's part (cut + re-derivation), ``plant_seconds`` the window's snapshot (incremental
    turtle + mesh patch, string preview), ``frame_seconds`` :meth:`PlantView.show_plant` and
    the paint (``paint_seconds``) of the first frame, a draft (1-pixel hairlines, none shorter than
    1.5 pixels on screen, no FXAA: see :mod:`ramure.app.desktop.view.plant_view`).  ``*_seconds`` is
    the time to that draft frame, the
    figure the targets are about.  ``*_polished_seconds`` adds the full-quality repaint
    (``*_polish_seconds``) that follows once the user pauses for ``polish_delay_seconds``
    (the wait itself is not counted: it is idle time in which further edits merge).
    ``still_frame_seconds``: a polished repaint with nothing changed; ``still_draft_*`` the
    same in the draft look.  CPU seconds (``*_cpu_seconds``) count this process's threads,
    llvmpipe's included.  "The frame" is on the screen (see :func:`_paint`): the native view
    (``window``: ``native``, the desktop's default on X11) swaps it within the paint; the
    QOpenGLWidget view (``native=False``) after Qt has composed the window.
    """
    from ramure.app.desktop import state
    from ramure.app.desktop.view.plant_view import POLISH_MS
    from ramure.app.model import Explorer

    ex = Explorer(str(ROOT / "grammars" / "honda_sympodial.lsys"), n=17)
    app, view = _plant_view(native=native)
    kind = "native" if view.native else "QOpenGLWidget"
    snap = state.take_snapshot(ex)
    _show(view, snap, True)
    view.polish()
    still, still_cpu, _ = _median_wall_cpu(lambda: _paint(view), repeat=5)
    view.draft()
    draft, draft_cpu, _ = _median_wall_cpu(lambda: _paint(view), repeat=5)
    view.polish()
    _paint(view)
    rng = np.random.default_rng(0)
    rows = {"regrow": [], "undo": []}

    def redraw():
        nonlocal snap
        t0, c0 = time.perf_counter(), time.process_time()
        snap = state.take_snapshot(ex, snap)
        t1, c1 = time.perf_counter(), time.process_time()
        view.show_plant(snap, state.cell_colors(snap.mesh, snap.selection, base=state.base_colors(snap.mesh)))
        assert view.drafting or not view.plant.large
        t2 = time.perf_counter()
        _paint(view)
        t3, c3 = time.perf_counter(), time.process_time()
        view.polish()  # what the polish timer does once the user pauses
        _paint(view)
        t4, c4 = time.perf_counter(), time.process_time()
        return t1 - t0, t3 - t1, t3 - t2, c1 - c0, c3 - c0, t4 - t3, c4 - c3

    def edit(action):
        t0, c0 = time.perf_counter(), time.process_time()
        action()
        regen, regen_cpu = time.perf_counter() - t0, time.process_time() - c0
        plant, frame, paint, plant_cpu, cpu, polish, polish_cpu = redraw()
        first = regen + plant + frame
        return first, regen, plant, frame, paint, regen_cpu + cpu, regen_cpu, plant_cpu, polish, first + polish, polish_cpu

    for k in range(5):
        leaves = ex.skeleton.leaf_id
        ex.select(rng.choice(leaves[len(leaves) // 3 :], 10, replace=False))
        rows["regrow"].append(edit(lambda: ex.regrow(seed=k)))  # noqa: B023 - called at once
        rows["undo"].append(edit(ex.undo))
        ex.redo()
        redraw()
    view.close()
    out = {
        "window": kind,
        "still_frame_seconds": round(still, 4),
        "still_frame_cpu_seconds": round(still_cpu, 4),
        "still_draft_seconds": round(draft, 4),
        "still_draft_cpu_seconds": round(draft_cpu, 4),
        "polish_delay_seconds": POLISH_MS / 1000,
    }
    for op, target in (("regrow", 0.1), ("undo", 0.05)):
        med = np.median(rows[op], axis=0)
        out.update(
            {
                f"{op}_seconds": round(med[0], 4),
                f"{op}_regen_seconds": round(med[1], 4),
                f"{op}_plant_seconds": round(med[2], 4),
                f"{op}_frame_seconds": round(med[3], 4),
                f"{op}_paint_seconds": round(med[4], 4),
                f"{op}_cpu_seconds": round(med[5], 4),
                f"{op}_regen_cpu_seconds": round(med[6], 4),
                f"{op}_plant_cpu_seconds": round(med[7], 4),
                f"{op}_polish_seconds": round(med[8], 4),
                f"{op}_polished_seconds": round(med[9], 4),
                f"{op}_polish_cpu_seconds": round(med[10], 4),
                f"{op}_target_seconds": target,
            }
        )
    return _plain(
        {
            "seconds": out["regrow_seconds"],
            **out,
            "modules": len(ex.derivation),
            "modules_per_second": int(len(ex.derivation) / out["regrow_seconds"]),
            "segments": len(ex.skeleton),
            "cells": ex.mesh.n_cells,
            "peak_mb": _peak_mb(),
            "ok": out["regrow_seconds"] <= 0.1 and out["undo_seconds"] <= 0.05,
        }
    )


def _median_ms(values) -> float | None:
    """The median of the figures that were measured (None: not measured), to 0.1 ms."""
    values = [v for v in values if v is not None]
    return round(statistics.median(values), 1) if values else None


def bench_desktop_edits_honda_n17(runs: int = 2):
    """Regrow 10 leaves, undo and redo in the real desktop window on Honda n = 17, each timed from
    the button's signal to the end of the first frame drawn with the new version (the worker's
    job, the window's slots, the view's update and the paint, through the event loop): what the
    user waits.  ``first_regrow_ms`` is a process's first edit (after a pause for the user to
    reach the button, in which the window warms the edit path up); ``regrow_ms`` the median of
    the four that follow, ``undo_ms`` / ``redo_ms`` the medians of five and four.  Median over
    ``runs`` fresh processes (:func:`desktop_memory`'s session, the dev venv's mypy hidden).
    ``peak_mb``: the largest of those processes' peaks (``VmHWM`` after the five edits), with
    the modules of the plant edited and regrown per second of the median regrow."""
    results = [desktop_memory(17, hide=("mypy",)) for _ in range(runs)]
    finished = [r for r in results if "frame_ms" in r]  # a process that failed has only "error"
    if not finished:
        return {"seconds": None, "error": results[0].get("error"), "ok": False}
    good = [r["frame_ms"] for r in finished]

    first = _median_ms([f["regrow"][0] for f in good])
    regrow = _median_ms([v for f in good for v in f["regrow"][1:]])
    undo = _median_ms([v for f in good for v in f["undo"]])
    redo = _median_ms([v for f in good for v in f["redo"]])
    modules = finished[0]["modules"]
    return _plain(
        {
            "seconds": None if regrow is None else round(regrow / 1000, 4),
            "modules": modules,
            "modules_per_second": int(modules / (regrow / 1000)) if regrow else None,
            "peak_mb": max(r["after_five_edits_mb"] for r in finished),
            "first_regrow_ms": first,
            "regrow_ms": regrow,
            "undo_ms": undo,
            "redo_ms": redo,
            "runs_ms": good,
            "target_regrow_ms": 100,
            "target_undo_ms": 50,
            "ok": regrow is not None and undo is not None and regrow <= 100 and undo <= 50,
        }
    )


def bench_rectangle_select_131k():
    """Rectangle select over Honda n=17 (131k segments), model side: project, select, recolour (<= 100 ms).

    ``box_seconds`` is the selection's oriented box (metrics.plant_obb) the desktop also draws.
    """
    from ramure.app.desktop import state
    from ramure.app.model import Explorer

    ex = Explorer(str(ROOT / "grammars" / "honda_sympodial.lsys"), n=17)
    snap = state.take_snapshot(ex)
    base = state.base_colors(snap.mesh)
    matrix = np.eye(4)
    matrix[0, 0] = matrix[1, 1] = 0.05
    times, boxes, found = [], [], []
    for rect in ((0, 0, 1000, 800), (0, 0, 500, 800), (500, 0, 1000, 400)) * 2:
        t0 = time.perf_counter()
        xy = state.project_to_display(matrix, snap.midpoints, (1000, 800))
        leaves = ex.leaves_in_rectangle(xy, rect)
        ex.select(leaves, "replace")
        found.append(len(leaves))
        snap = state.take_snapshot(ex, snap)
        state.cell_colors(snap.mesh, snap.selection, None, base=base)
        times.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        state.selection_box_lines(snap.skeleton, snap.selection)
        boxes.append(time.perf_counter() - t0)
    seconds = statistics.median(times)
    return _plain(
        {
            "seconds": round(seconds, 4),
            "box_seconds": round(statistics.median(boxes), 4),
            "modules": len(ex.derivation),
            "modules_per_second": int(len(ex.derivation) / seconds),
            "segments": len(snap.midpoints),
            "cells": snap.mesh.n_cells,
            "selected_max": max(found),
            "target_seconds": 0.1,
            "peak_mb": _peak_mb(),
            "ok": seconds <= 0.1,
        }
    )


def _plain(record):
    """JSON-ready: numpy scalars as Python numbers."""
    return {k: v.item() if isinstance(v, np.generic) else v for k, v in record.items()}


def _nbytes(*arrays):
    return sum(np.asarray(a).nbytes for a in arrays if a is not None)


_DESKTOP_STAGES = """
import json, pathlib, sys, tempfile
for name in {hide!r}:  # hidden as if not installed (pyvista imports mypy whenever it is installed)
    sys.modules[name] = None

def memory():
    fields = dict(line.split(":", 1) for line in open("/proc/self/status"))
    return [round(int(fields[k].split()[0]) / 1024, 1) for k in ("VmRSS", "VmHWM")]

stages = {{}}
def stage(name):
    stages[name] = memory()

stage("python")
from PySide6.QtCore import QSettings
from ramure.app.desktop.launch import make_application
from ramure.app.desktop.window import MainWindow
from ramure.app.model import Explorer
app = make_application()
stage("imports")
explorer = Explorer({grammar!r}, n={n})
stage("derivation + skeleton")
explorer.mesh
stage("mesh")
settings = QSettings(str(pathlib.Path(tempfile.mkdtemp()) / "s.ini"), QSettings.Format.IniFormat)
window = MainWindow(explorer, settings=settings, ask=False)
stage("window built")
window.resize(1400, 880)
window.show()
for _ in range(20):
    app.processEvents()
window.controller.wait_idle()
stage("window shown")
window.view.redraw(now=True)
for _ in range(5):
    app.processEvents()
stage("frame rendered")
peak = memory()[1]
# what the resident pages are at that moment: private memory, mapped files (libraries' code and
# relocations, shared with other processes), shared memory (the X server's window image)
fields = dict(line.split(":", 1) for line in open("/proc/self/status"))
composition = {{k[3:].lower(): round(int(fields[k].split()[0]) / 1024, 1) for k in ("RssAnon", "RssFile", "RssShmem")}}
# a click on the trunk: the picker and its cell locator, the selection recoloured, its box drawn
x, y = window.view.project(window.controller.snapshot.midpoints[:1])[0]
picked = window.view.click_at(float(x), float(y))


# an edit's time to its frame: from the button's signal to the end of the first frame rendered
# once the new version is published (frames rendered while the job runs do not count)
import time
from PySide6.QtCore import QEventLoop, QTimer
frames = {{"regrow": [], "undo": [], "redo": []}}
clock = {{}}
def frame_end(*_args):
    if clock and window.controller.snapshot.version != clock["version"] and "ms" not in clock:
        clock["ms"] = round((time.perf_counter() - clock["t0"]) * 1e3, 1)
        clock["loop"].quit()
window.view.plotter.ren_win.AddObserver("EndEvent", frame_end)


def edit(kind, name):
    clock.clear()
    loop = QEventLoop()  # Qt's own event loop, idle between events, as in the running window
    QTimer.singleShot(5000, loop.quit)
    clock.update(version=window.controller.snapshot.version, t0=time.perf_counter(), loop=loop)
    getattr(window.regen, kind).emit()
    loop.exec()
    frames[kind].append(clock.get("ms"))
    drawn(name)


def drawn(name):  # the job finished, its events handled, the view repainted: then the stage
    window.controller.wait_idle()
    for _ in range(5):
        app.processEvents()
    window.view.redraw(now=True)
    stage(name)


def pause(seconds):
    loop = QEventLoop()
    QTimer.singleShot(int(seconds * 1000), loop.quit)
    loop.exec()


drawn("first pick")
# Regrow 10 leaves (the Regrow button), then undo: the plant before the edit is kept for undo
leaves = window.controller.snapshot.segment_leaf
window.controller.select(sorted(set(int(v) for v in leaves[len(leaves) // 3::len(leaves) // 15][:10])))
window.controller.wait_idle()
pause(0.8)  # the user moves to the button (the edit warm-up runs meanwhile)
edit("regrow", "regrow")
edit("undo", "undo")
after_edits = memory()[1]
# four more edits of 10 leaves each (300-1,100 modules regrown), as a user makes them: redo,
# select, regrow, undo (what an editing session holds)
for k in range(4):
    edit("redo", f"redo {{k + 1}}")
    leaves = window.controller.snapshot.segment_leaf
    step = max(1, len(leaves) // 15)
    window.controller.select(sorted(set(int(v) for v in leaves[len(leaves) // 3 + 101 * (k + 1) :: step][:10])))
    window.controller.wait_idle()
    pause(0.8)
    edit("regrow", f"regrow {{k + 2}}")
    edit("undo", f"undo {{k + 2}}")
modules = sorted(m for m in ("numba", "matplotlib", "scipy.sparse", "networkx", "mypy", "ramure.gmap", "vtkmodules.all")
                 if sys.modules.get(m) is not None)
# VmHWM: this process's own peak (ru_maxrss would carry the parent's over fork and exec)
print(json.dumps({{"peak_mb": peak, "after_pick_mb": stages["first pick"][1], "after_edits_mb": after_edits,
                  "after_five_edits_mb": memory()[1],
                  "peak_composition_mb": composition,
                  "picked_cell": picked, "version": window.controller.snapshot.version, "stages": stages,
                  "modules": len(explorer.derivation), "loaded": modules, "frame_ms": frames}}))
"""


def _desktop_command():
    """The command prefix that gives the child a display: none needed when there is one (or an
    off-screen platform is asked for), else ``xvfb-run`` (software OpenGL, as in CI)."""
    import os
    import shutil

    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or os.environ.get("QT_QPA_PLATFORM"):
        return []
    xvfb = shutil.which("xvfb-run")
    return [xvfb, "-a", "-s", "-screen 0 1400x900x24"] if xvfb else None


def desktop_memory(
    n: int = 17,
    grammar: str | None = None,
    hide: tuple[str, ...] = (),
    numba_cache: str | None = None,
    cgroup: pathlib.Path | None = None,
) -> dict:
    """Peak RSS (``VmHWM``) of a fresh process that opens the real desktop window on ``grammar``
    (default Honda sympodial) derived ``n`` steps, shows it and renders a frame (``peak_mb``),
    then picks the trunk with a click (``after_pick_mb``), regrows 10 leaves and undoes
    (``after_edits_mb``), then redoes, regrows 10 other leaves and undoes four times more
    (``after_five_edits_mb``: what an editing session holds); with the RSS after each stage (``stages``: name -> [RSS, peak so
    far] in MB).  ``hide`` names modules the child sees as not installed (``("mypy",)``: the
    dev venv's mypy, which pyvista imports only because it is there, 24 MB).  ``numba_cache``:
    the child's ``NUMBA_CACHE_DIR`` (an empty folder: a first run, every kernel compiled).
    ``peak_composition_mb``: the resident pages at the first frame by kind (``anon``: private
    memory; ``file``: mapped libraries; ``shmem``: the X server's window image).
    ``frame_ms``: each regrow, undo and redo from the button's signal to the end of the first
    frame drawn with the new version, Qt's event loop running between events as in the window
    (:func:`bench_desktop_edits_honda_n17`); before each regrow the session pauses 0.8 s, the
    user reaching for the button.  ``cgroup``: a memory cgroup folder the child runs in (with
    ``xvfb-run``, the X server too; see ``bench_memory_limit.py``).
    ``{"error": ...}`` when the window cannot be opened here (no Qt, no display)."""
    import os
    import subprocess
    import sys

    prefix = _desktop_command()
    if prefix is None:
        return {"error": "no display and no xvfb-run"}
    grammar = grammar or str(ROOT / "grammars" / "honda_sympodial.lsys")
    code = _DESKTOP_STAGES.format(grammar=grammar, n=n, hide=tuple(hide))
    try:
        env = {**os.environ, **({"NUMBA_CACHE_DIR": numba_cache} if numba_cache else {})}
        join = None if cgroup is None else (lambda: (cgroup / "cgroup.procs").write_text(str(os.getpid())))
        out = subprocess.run(
            [*prefix, sys.executable, "-c", code], capture_output=True, text=True, timeout=900, env=env, preexec_fn=join
        )
    except subprocess.SubprocessError as exc:
        return {"error": repr(exc)}
    return child_json(out)


_PLANT_SECONDS = """
import sys, time
t0 = time.perf_counter()
from ramure.app.model import Explorer
ex = Explorer({grammar!r}, n={n})
ex.mesh
print(round(time.perf_counter() - t0, 2))
"""


def _first_run(n: int = 17) -> dict:
    """Seconds to Honda ``n`` with its mesh in a fresh process whose numba cache is empty (every
    kernel compiled: the first run after an install), then in one that loads that cache; and
    the desktop's peak on such a first run.  The cache folder is removed afterwards."""
    import os
    import shutil
    import subprocess
    import sys
    import tempfile

    folder = tempfile.mkdtemp(prefix="ramure-numba-")
    try:
        code = _PLANT_SECONDS.format(grammar=str(ROOT / "grammars" / "honda_sympodial.lsys"), n=n)
        env = {**os.environ, "NUMBA_CACHE_DIR": folder}

        def seconds():
            out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=900, env=env)
            return float(out.stdout.split()[-1]) if out.returncode == 0 else None

        compiled, cached = seconds(), seconds()
        shutil.rmtree(folder)
        desktop = desktop_memory(n, hide=("mypy",), numba_cache=folder)
        return {"compile_seconds": compiled, "cached_seconds": cached, "desktop_peak_mb": desktop.get("peak_mb")}
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _model_record() -> dict:
    """The model's bytes for Honda n = 17: history tree (with the string), skeleton (+ trace) and
    mesh per module, and the mesh's cell data per cell."""
    from ramure.app.model import Explorer

    ex = Explorer(str(ROOT / "grammars" / "honda_sympodial.lsys"), n=17)
    tree = ex.derivation.tree
    modules = len(ex.derivation)
    tree_bytes = (
        sum(
            getattr(tree, name).nbytes
            for name in (
                "symbol",
                "nparams",
                "parent",
                "step",
                "rule",
                "index_in_rule",
                "child_start",
                "child_count",
                "alive",
                "params",
            )
        )
        + tree.leaves.nbytes
    )
    sk = ex.skeleton
    skeleton_bytes = (
        _nbytes(sk.start, sk.end, sk.base_radius, sk.top_radius, sk.order, sk.leaf_id, sk.color, sk.normal, sk.parent)
        + sk.extra["trace"].nbytes()
    )
    mesh = ex.mesh
    mesh_bytes = int(mesh.actual_memory_size) * 1024
    record = {
        "seconds": 0.0,
        "modules": modules,
        "tree_nodes": len(tree),
        "segments": len(sk),
        "cells": mesh.n_cells,
        "tree_bytes_per_module": round(tree_bytes / modules, 1),
        "skeleton_bytes_per_module": round(skeleton_bytes / modules, 1),
        "mesh_bytes_per_module": round(mesh_bytes / modules, 1),
        "cell_data_bytes_per_cell": round(sum(np.asarray(a).nbytes for a in mesh.cell_data.values()) / mesh.n_cells, 1),
        "total_mb": round((tree_bytes + skeleton_bytes + mesh_bytes) / 2**20, 1),
    }
    return record


def bench_memory_per_module_honda_n17(repeats: int = 3):
    """Bytes per module of the history tree, the skeleton (+ trace) and the mesh, Honda n=17;
    the desktop window's peak RSS with that plant shown (<= 600 MB): median of ``repeats``
    fresh processes, the stages of the median run, and the same window on n=4 (``floor_mb``:
    what Qt, VTK, numba and one software-OpenGL context cost before any large plant);
    ``desktop_peak_without_mypy_mb``: one more run with the dev venv's mypy hidden (what a
    user's install, without mypy, peaks at).

    The desktop runs load the kernels from numba's cache, as every run after the first does.
    ``first_run``: the first run after an install (an empty ``NUMBA_CACHE_DIR``): the seconds
    to a plant with its mesh (fresh process, every kernel compiled) against the same with the
    cache it wrote, and the desktop's peak while compiling (numba's whole compiler loaded)."""
    record = _model_record()
    runs = [desktop_memory(17) for _ in range(repeats)]
    peaks = sorted((r["peak_mb"], i) for i, r in enumerate(runs) if "peak_mb" in r)
    if not peaks:
        return _plain(
            {**record, "desktop_peak_mb": None, "desktop_error": runs[0].get("error"), "target_peak_mb": 600, "ok": False}
        )
    median = runs[peaks[len(peaks) // 2][1]]
    floor = desktop_memory(4)
    user = desktop_memory(17, hide=("mypy",))
    first_run = _first_run(17)
    return _plain(
        {
            **record,
            "desktop_peak_mb": median["peak_mb"],
            "after_first_pick_mb": median["after_pick_mb"],
            "after_regrow_undo_mb": median["after_edits_mb"],
            "after_five_edits_mb": median.get("after_five_edits_mb"),
            "desktop_peaks_mb": [p for p, _ in peaks],
            "desktop_stages_mb": median["stages"],
            "desktop_loaded": median["loaded"],
            "desktop_peak_without_mypy_mb": user.get("peak_mb"),
            "desktop_stages_without_mypy_mb": user.get("stages"),
            "desktop_peak_composition_mb": user.get("peak_composition_mb"),
            "floor_mb": floor.get("peak_mb"),
            "floor_stages_mb": floor.get("stages"),
            "first_run": first_run,
            "target_peak_mb": 600,
            "ok": median["peak_mb"] <= 600,
        }
    )
