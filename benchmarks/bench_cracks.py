"""Cracks (issue 18) against the thesis's Table 5.1 sizes (Desbenoit 2006).

Table 5.1 gives sizes, no compute times (Centrino 1.3 GHz). The mushroom: a 63-node pattern on a
38,160-triangle object. Target: projection + sweep + Boolean <= 0.5 s, here on a closed
ellipsoid of 37,524 triangles.
"""
from __future__ import annotations

import time

import pyvista as pv

from ramure.gmap.cracks import carve, random_pattern
from ramure.gmap.trimesh import from_polydata


def bench_crack_63_nodes_on_38k_triangles():
    mesh = from_polydata(pv.ParametricEllipsoid(2, 2, 2, u_res=160, v_res=120))
    pattern = random_pattern(63, seed=2, length=0.15, width=0.02, depth=0.04)
    carve(mesh, pattern, (0, 0, 2.0), (1, 0, 0))  # compile the walker once
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        crack = carve(mesh, pattern, (0, 0, 2.0), (1, 0, 0))
        best = min(best, time.perf_counter() - t0)
    facts = crack.facts()
    return {"seconds": round(best, 4), "target_seconds": 0.5, "ok": best <= 0.5, "nodes": facts["nodes"],
            "triangles_object": facts["triangles_object"], "triangles_crack": facts["triangles_crack"],
            "triangles_result": facts["triangles_result"], "watertight": facts["watertight"]}
