"""3G-map fruit benchmarks against the thesis's i7-3770 figures divided by ten.

Reference (Bohl 2015, Table 2.26): round tomato 422 ms, twice surface-subdivided
1,995 ms, twice volume-subdivided (384,000 darts) 3,689 ms.  Each timing here
includes building the fruit and the validity check; best of a few repeats.
"""

from __future__ import annotations

import time

from ramure.gmap.kernel import subdivide
from ramure.gmap.organs.fruit import build_fruit
from benchtools import best


def _bench_build(make, repeats, target, reference=None):
    """Best time of ``make()`` plus the validity check, with the map's figures."""

    def run():
        gm = make()
        return gm, gm.is_valid()

    seconds, (gm, valid) = best(run, repeats)
    c = gm.counts()
    record = {
        "seconds": round(seconds, 6),
        "target_seconds": target,
        "ok": bool(valid and seconds <= target),
        "darts": c["darts"],
        "vertices": c["vertices"],
        "volumes": c["volumes"],
        "valid": bool(valid),
    }
    if reference is not None:
        record["reference_seconds"] = reference
    return record


def bench_round_tomato():
    """Trunk order 10, precision 10, 100 branches: 6,000 darts (thesis: 422 ms)."""
    return _bench_build(lambda: build_fruit("round_tomato"), 20, 0.040, 0.422)


def bench_round_tomato_surface2():
    """Round tomato, two surface subdivisions: 96,000 darts (thesis: 1,995 ms)."""
    return _bench_build(lambda: subdivide.surface(build_fruit("round_tomato"), 2), 7, 0.200, 1.995)


def bench_round_tomato_volume2():
    """Round tomato, two volume subdivisions: 384,000 darts (thesis: 3,689 ms)."""
    return _bench_build(lambda: subdivide.volume(build_fruit("round_tomato"), 2), 5, 0.370, 3.689)


def bench_million_darts():
    """A fruit of 1,020,000 darts (precision 170, 100 branches per ring) built and validated."""
    return _bench_build(lambda: build_fruit("round_tomato", precision=170, ph=100), 3, 2.0)


def bench_tomato_with_tissues():
    """Round tomato, two volume subdivisions, tissues and 120 rounded seeds (no thesis figure)."""
    return _bench_build(lambda: build_fruit("round_tomato", volume_levels=2), 3, 3.0)


# ---------------------------------------------------------------- kernel (issue 13)
def _timings(fn, repeats):
    times, result = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    times.sort()
    return times, result


def bench_cut_map():
    """cut_map on a 90,000-dart tomato (precision 15, 100 sides; the issue's reference wood has ~86,400).

    Oblique plane through the centre; median of 7 after one warm-up; the kept volume is checked
    against the VTK clip of the same model.
    """
    from ramure.gmap.kernel.cut import cut_map, plane_cut
    from ramure.gmap.kernel.pyvista import to_unstructured_grid

    gm = build_fruit("round_tomato", precision=15, ph=100)
    gm.cells(0)
    normal = (0.3, 0.2, 1.0)
    cut_map(gm, normal)
    times, cut = _timings(lambda: cut_map(gm, normal), 7)
    median = times[len(times) // 2]
    got = to_unstructured_grid(cut).volume
    ref = plane_cut(gm, normal, None, mode="clip").volume
    valid = cut.is_valid()
    return {
        "seconds": round(median, 6),
        "best_seconds": round(times[0], 6),
        "target_seconds": 0.100,
        "ok": bool(valid and median <= 0.100),
        "darts": gm.n_darts,
        "kept_darts": cut.n_darts,
        "darts_per_second": round(gm.n_darts / median),
        "volume_error": abs(got - ref) / ref,
        "valid": bool(valid),
    }


def _ring_trunk(units=10, sides=16, layers=20, embed_each=True):
    """A wood-like map: ``units`` stacked ``sides``-prisms, ``layers`` cube rings grown and joined."""
    import numpy as np

    from ramure.gmap import GMap3
    from ramure.gmap.kernel.embedding import grow
    from ramure.gmap.kernel.topology import assert_solid

    gm = GMap3()
    trunk = gm.add_prisms(sides, units, origins=[[i, 0.0, 0.0] for i in range(units)], sizes=[[1.0, 1.0, 1.0]] * units)
    ids = gm.dart_volume[trunk].astype(np.int64)
    gm.sew3(gm.face_of(ids[:-1], "E"), gm.face_of(ids[1:], "O"))
    labels = [f"C{j + 1}" for j in range(sides)] * units
    faces = gm.face_of(np.repeat(ids, sides), labels)
    _below = None
    for _ in range(layers):
        ring = grow(gm, faces, 4, height=0.1).reshape(units, sides)
        gm.identify(gm.face_of(ring.ravel(), "C2"), gm.face_of(np.roll(ring, -1, axis=1).ravel(), "C4"))
        gm.identify(gm.face_of(ring[:-1].ravel(), "C3"), gm.face_of(ring[1:].ravel(), "C1"))
        faces = gm.face_of(ring.ravel(), "E")
        if embed_each:
            gm.embed()
            assert_solid(gm)
    gm.embed()
    return gm


def bench_ring_growth():
    """Kernel part of wood growth: 10 units x 16 sides x 20 ring layers (grow + 2 identify per layer),
    embedding, validity and chi checks after every layer (the engine adds its rule matching on top).
    Median of 3."""
    times, gm = _timings(_ring_trunk, 3)
    median = times[len(times) // 2]
    return {
        "seconds": round(median, 6),
        "target_seconds": 0.5,
        "ok": bool(median <= 0.5),
        "darts": gm.n_darts,
        "volumes": gm.n_volumes,
        "darts_per_second": round(gm.n_darts / median),
    }
