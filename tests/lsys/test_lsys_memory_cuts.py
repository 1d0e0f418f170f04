"""Memory of large plants (issue 14): what ``import ramure.lsys`` loads, the dtypes of the turtle's
trace and of the mesh, and the bytes an interpretation allocates per module."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from ramure.lsys import LSystem


def test_importing_lsys_does_not_load_numba_until_a_polygon_is_triangulated():
    # numba costs about 65 MB: a CLI or metrics user who never runs a kernel must not pay it
    code = (
        "import sys; import ramure.lsys, ramure.lsys.polygons, ramure.lsys.turtle, ramure.lsys.geometry; "
        "a = 'numba' in sys.modules; "
        "from ramure.lsys.polygons import triangulate; "
        "tris, owner = triangulate([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [0, 4]); "
        "print(a, 'numba' in sys.modules, len(tris), owner.tolist())"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.split() == ["False", "True", "2", "[0,", "0]"], out.stderr
