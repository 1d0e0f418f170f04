"""Memory of the app layer with large plants (issue 14): the notebook picker imports one VTK
class, not the whole ``vtk`` package (about 50 MB); the explorer keeps what undo needs."""

from __future__ import annotations

import subprocess
import sys


def test_the_notebook_picker_does_not_import_the_whole_vtk_package():
    code = (
        "import sys, types\n"
        "from ramure.app.jupyter.view import ClickPicker\n"
        "seen = []\n"
        "iren = types.SimpleNamespace(add_observer=lambda event, fn: seen.append(event))\n"
        "picker = ClickPicker(types.SimpleNamespace(iren=iren), print)\n"
        "print('vtk' in sys.modules, 'vtkmodules.all' in sys.modules, type(picker.picker).__name__, len(seen))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.split() == ["False", "False", "vtkCellPicker", "3"], out.stderr
