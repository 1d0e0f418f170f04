"""Polygons do not slow the turtle (issue 15): a plant with 131,068 leaf polygons (ABOP fig. 1.26's
8-vertex leaf, {+f-ff-f+|+f-ff-f}, four per internode of a 32,767-segment binary plant)
interprets and meshes in <= 1 s.

Timed: the turtle over the derived string (:meth:`Derivation.skeleton`: kernel, polygon
assembly) plus the mesh (:meth:`Skeleton.to_polydata`: tubes with the desktop's number of
sides, polygon triangulation, cell data).  The derivation itself is not timed.  Also
reported: the triangulation alone, and the same plant with its leaves as plain modules
(what the turtle costs without polygons).
"""

from __future__ import annotations

from benchtools import best

from ramure.app.model import mesh_sides
from ramure.lsys import LSystem

PLANT = """#module plant
#angle 18
n: {n}
w: plant
p:
  plant -> F[+(40)'{{+f-ff-f+|+f-ff-f}}][-(40)'{{+f-ff-f+|+f-ff-f}}]/(90)...
           [+(40)'{{+f-ff-f+|+f-ff-f}}][-(40)'{{+f-ff-f+|+f-ff-f}}]/(45)[&(30)plant][^(30)plant]
"""
TARGET_SECONDS = 1.0


def _derive(n=15, leaf=None):
    text = PLANT.format(n=n)
    if leaf is not None:
        text = text.replace("'{+f-ff-f+|+f-ff-f}", leaf)
    return LSystem.from_text(text).derive()


def bench_polygons():
    d = _derive()
    sk = d.skeleton()  # warm (numba loads)
    sides = mesh_sides(len(sk))

    def run():
        skeleton = d.skeleton()
        return skeleton, skeleton.to_polydata(sides=sides)

    seconds, (sk, mesh) = best(run)
    turtle_seconds, _ = best(d.skeleton)
    tri_seconds, _ = best(sk.polygons.triangles)
    plain = _derive(leaf="'+f-ff-f+|+f-ff-f")  # same moves, no polygons
    plain_seconds, _ = best(plain.skeleton)
    return {
        "seconds": round(seconds, 4),
        "target_seconds": TARGET_SECONDS,
        "ok": seconds <= TARGET_SECONDS,
        "polygons": len(sk.polygons),
        "modules": len(d),
        "segments": len(sk),
        "tube_sides": sides,
        "cells": mesh.n_cells,
        "turtle_seconds": round(turtle_seconds, 4),
        "triangulate_seconds": round(tri_seconds, 4),
        "turtle_without_polygons_seconds": round(plain_seconds, 4),
    }


if __name__ == "__main__":
    print(bench_polygons())


def bench_polygons_regrow():
    """Redraw after regrowing 10 leaves of the 131k-polygon plant: the turtle over the regrown
    regions only (polygons spliced, :func:`ramure.lsys.interpretation.turtle.reinterpret`) and the patched mesh
    (:func:`ramure.lsys.interpretation.geometry.patch_polydata`).  Target: half of what the full turtle + mesh
    costs.  The regrow itself (cut, re-derivation) is reported apart, as ``edit_seconds``."""
    import time

    import numpy as np

    from ramure.lsys.interpretation.geometry import patch_polydata
    from ramure.lsys.regeneration.regen import Session
    from ramure.lsys.interpretation.turtle import changed_spans, reinterpret

    session = Session(LSystem.from_text(PLANT.format(n=15)), seed=1)
    old = session.derivation.skeleton()
    sides = mesh_sides(len(old))
    old_mesh = old.to_polydata(sides=sides)
    full_seconds, _ = best(lambda: session.derivation.skeleton().to_polydata(sides=sides), repeats=2)
    rng = np.random.default_rng(3)
    redraw, edit = [], []
    for k in range(3):
        before = session.tree.leaves
        t0 = time.perf_counter()
        session.regrow(rng.choice(old.polygons.leaf_id, size=10, replace=False), seed=k)
        t1 = time.perf_counter()
        spans = changed_spans(before, session.tree.leaves, session.tree.size)
        new = reinterpret(session.lsystem, session.tree, old, session.tree.leaves, *spans)
        mesh = patch_polydata(old_mesh, new, sides)
        t2 = time.perf_counter()
        assert "reuse" in new.extra
        edit.append(t1 - t0)
        redraw.append(t2 - t1)
        old, old_mesh = new, mesh
    seconds = float(np.median(redraw))
    return {
        "seconds": round(seconds, 4),
        "target_seconds": round(full_seconds / 2, 4),
        "ok": seconds <= full_seconds / 2,
        "full_turtle_and_mesh_seconds": round(full_seconds, 4),
        "edit_seconds": round(float(np.median(edit)), 4),
        "polygons": len(old.polygons),
        "cells": mesh.n_cells,
    }
