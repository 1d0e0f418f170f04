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


def test_a_module_a_cut_removed_from_the_string_cannot_be_selected():
    import numpy as np
    import pytest

    from ramure.app.model import Explorer
    from ramure.errors import ValueRefused

    ex = Explorer("n: 2\nw: A\np:\n  A -> F[+B%C]F\n  B -> B\n", n=2)
    tree = ex.derivation.tree
    assert ex.derivation.to_string() == "F[+B]F"
    symbols = np.array(ex.lsystem.symbols)[tree.symbol]
    cut = int(np.flatnonzero(symbols == "C")[0])  # alive and childless, but out of the string
    b = int(tree.leaves[3])
    ex.select([b])
    with pytest.raises(ValueRefused, match="leaf"):
        ex.select([b, cut], mode="add")
    with pytest.raises(ValueRefused):
        ex.select([0])  # the axiom's A: rewritten, not a leaf
    assert ex.selection == [b]
    ex.select(tree.leaves.tolist())
    assert ex.selection == sorted(tree.leaves.tolist())


def test_selecting_in_a_large_plant_does_not_compute_the_leaf_spans():
    import tracemalloc

    from ramure.app.model import Explorer

    ex = Explorer("grammars/honda_sympodial.lsys", n=13)
    tree = ex.derivation.tree
    leaves = ex.skeleton.leaf_id
    tracemalloc.start()
    try:
        ex.select(leaves[::97].tolist())
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert ex.selection == sorted(set(leaves[::97].tolist()))
    # a string mask, 1 byte per node; the leaf spans took 16 (two int64 arrays) and stay for the cut
    assert peak < 4 * tree.size
    ex.regrow(seed=2)  # the cut still finds its leaves after such a selection
    ex.select(ex.skeleton.leaf_id[:3].tolist())
    assert len(ex.selection) == 3
