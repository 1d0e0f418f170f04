"""What the desktop loads at start (issue 14, memory).

It imports the VTK classes it uses, never the ``vtk`` package: ``import vtk`` loads every VTK
module, about 60 MB more resident memory in the window (measured by
``benchmarks/bench_speed.py``'s desktop memory), where ``from vtkmodules.vtkRenderingCore
import vtkActor`` loads one.  And a plant drawn from numba's cache does not load numba's
compiler registries (about 50 MB with the ``scipy.linalg`` they import), nor what only an edit
needs (networkx for the cut graph) nor packages the desktop never uses at start.
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
import pytest

from desktop_helpers import ROOT

DESKTOP = ROOT / "app" / "desktop"


def _whole_vtk_imports(path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import) and any(a.name == "vtk" or a.name.startswith("vtk.") for a in node.names):
            yield node.lineno
        if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "vtk":
            yield node.lineno


def test_no_desktop_module_imports_the_whole_vtk_package():
    paths = sorted(DESKTOP.rglob("*.py"))  # the view's modules are in view/
    assert DESKTOP / "view" / "native_view.py" in paths
    found = [f"{path.relative_to(DESKTOP)}:{line}" for path in paths for line in _whole_vtk_imports(path)]
    assert found == []


_START = """
import json, sys
import ramure.app.desktop.window
from ramure.app.model import Explorer
explorer = Explorer({grammar!r}, n={n})
explorer.skeleton, explorer.mesh
watch = ("numba", "numba.np.arraymath", "scipy.linalg", "scipy.sparse", "networkx", "vtkmodules.all",
         "sklearn", "pandas", "ramure.gmap", "ramure.studies")
print(json.dumps({{name: name in sys.modules for name in watch}}))
"""


@pytest.mark.parametrize("n", [8, 14])
def test_a_plant_drawn_from_the_kernel_cache_loads_no_compiler_and_nothing_an_edit_needs(n):
    from desktop_helpers import HONDA

    code = _START.format(grammar=str(HONDA), n=n)
    runs = [subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300) for _ in range(2)]
    assert all(r.returncode == 0 for r in runs), runs[-1].stderr
    loaded = json.loads(runs[1].stdout.strip().splitlines()[-1])  # the first run may have compiled (fresh clone)
    # n = 14 (180,213 modules): the turtle ran its kernel; n = 8 (2,805): the plain walk, no numba at all
    assert loaded.pop("numba") is (n == 14)
    assert not any(loaded.values()), loaded  # kernels loaded from the cache: no numba registries, no scipy.linalg


_SCAN = """
import json, linecache, sys
import ramure.app.desktop.window
import matplotlib.backends.backend_qtagg  # what the PCA dock imports with its first variants
flags = sys.modules["shibokensupport.feature"].pyside_feature_dict
modules = ("ramure.app.desktop.view.plant_view", "matplotlib.backends.qt_compat", "pyvista.core.pointset", "numpy.linalg",
           "matplotlib.figure")
print(json.dumps({"cached_files": len(linecache.cache), "flags": [flags.get(name) for name in modules]}))
"""


def test_pyside_does_not_keep_the_source_of_every_module_imported_after_it():
    # PySide6's import hook read each new module's source through linecache (760 files, about
    # 50 MB kept in the desktop); qt_fix.skip_source_scan reads the file without keeping it
    done = subprocess.run([sys.executable, "-c", _SCAN], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    found = json.loads(done.stdout.strip().splitlines()[-1])
    assert found["cached_files"] < 20  # over 500 without the fix
    # the same answers as PySide6's own test: modules that mention PySide6 can use __feature__ (0),
    # the others are ignored by feature switching (-1)
    assert found["flags"] == [0, 0, -1, -1, -1]


_FALLBACK = """
import json, sys
from ramure.app.desktop.launch import make_application
from ramure.app.desktop.view.plant_view import PlantView
app = make_application([])
view = PlantView()
print(json.dumps({"native": view.native, "pyvistaqt": "pyvistaqt" in sys.modules,
                  "kind": type(view.plotter).__name__}))
"""


def _plant_view_in(platform):
    import os

    env = dict(os.environ, QT_QPA_PLATFORM=platform, RAMURE_GL_WIDGET="0")
    done = subprocess.run([sys.executable, "-c", _FALLBACK], capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_pyvistaqt_is_loaded_only_for_its_qopenglwidget_fallback():
    # the native view (X11) does not need pyvistaqt: 6-12 MB less in the desktop
    native = _plant_view_in("xcb")
    assert native == {"native": True, "pyvistaqt": False, "kind": "NativeInteractor"}
    fallback = _plant_view_in("offscreen")  # Qt's offscreen platform: pyvistaqt's QOpenGLWidget
    assert fallback == {"native": False, "pyvistaqt": True, "kind": "QtInteractor"}


_ARENAS = """
import ctypes, os, re, sys, tempfile, threading
{setup}
def grow():  # small blocks from a second thread: glibc gives it an arena of its own by default
    blocks = [bytearray(200) for _ in range(20_000)]
    del blocks
thread = threading.Thread(target=grow)
thread.start()
thread.join()
libc = ctypes.CDLL("libc.so.6")
libc.fopen.restype = ctypes.c_void_p
path = os.path.join(tempfile.mkdtemp(), "info.xml")
out = libc.fopen(path.encode(), b"w")
libc.malloc_info(0, ctypes.c_void_p(out))
libc.fclose(ctypes.c_void_p(out))
print(len(re.findall('<heap nr=', open(path).read())))
"""


def _arenas(setup: str) -> int:
    run = subprocess.run([sys.executable, "-c", _ARENAS.format(setup=setup)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    return int(run.stdout.split()[-1])


def test_the_desktop_serves_its_threads_from_one_malloc_arena():
    import ctypes.util

    if ctypes.util.find_library("c") != "libc.so.6":
        pytest.skip("glibc's malloc only")
    assert _arenas("") == 2  # the check sees a thread's own arena when nothing is asked
    setup = "from ramure.app.desktop.launch import one_malloc_arena\nassert one_malloc_arena()"
    assert _arenas(setup) == 1
