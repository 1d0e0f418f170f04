"""3G-map fruit benchmarks against the thesis's i7-3770 figures divided by ten.

Reference (Bohl 2015, Table 2.26): round tomato 422 ms, twice surface-subdivided
1,995 ms, twice volume-subdivided (384,000 darts) 3,689 ms.  Each timing here
includes building the fruit and the validity check; best of a few repeats.
"""
from __future__ import annotations

import time

from ramure.gmap import subdivide
from ramure.gmap.fruit import build_fruit


def _best(fn, repeats=5):
    best, result = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
    return best, result


def _bench_build(make, repeats, target, reference=None):
    """Best time of ``make()`` plus the validity check, with the map's figures."""
    def run():
        gm = make()
        return gm, gm.is_valid()

    seconds, (gm, valid) = _best(run, repeats)
    c = gm.counts()
    record = {"seconds": round(seconds, 6), "target_seconds": target, "ok": bool(valid and seconds <= target),
              "darts": c["darts"], "vertices": c["vertices"], "volumes": c["volumes"], "valid": bool(valid)}
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
