"""3G-map fruit benchmarks against the thesis's i7-3770 figures divided by ten.

Reference (Bohl 2015, Table 2.26): round tomato 422 ms, twice surface-subdivided
1,995 ms, twice volume-subdivided (384,000 darts) 3,689 ms.  Each timing here
includes building the fruit and the validity check; best of a few repeats.
"""
from __future__ import annotations

import time

from gmap import subdivide
from gmap.fruit import build_fruit


def _best(fn, repeats=5):
    best, result = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
    return best, result


def _record(seconds, target, gm, valid, **extra):
    c = gm.counts()
    return {"seconds": round(seconds, 6), "target_seconds": target, "ok": bool(valid and seconds <= target),
            "darts": c["darts"], "vertices": c["vertices"], "volumes": c["volumes"], "valid": bool(valid),
            **extra}


def bench_round_tomato():
    """Trunk order 10, precision 10, 100 branches: 6,000 darts (thesis: 422 ms)."""
    def run():
        gm = build_fruit("round_tomato")
        return gm, gm.is_valid()

    seconds, (gm, valid) = _best(run, 20)
    return _record(seconds, 0.040, gm, valid, reference_seconds=0.422)


def bench_round_tomato_surface2():
    """Round tomato, two surface subdivisions: 96,000 darts (thesis: 1,995 ms)."""
    def run():
        gm = subdivide.surface(build_fruit("round_tomato"), 2)
        return gm, gm.is_valid()

    seconds, (gm, valid) = _best(run, 7)
    return _record(seconds, 0.200, gm, valid, reference_seconds=1.995)


def bench_round_tomato_volume2():
    """Round tomato, two volume subdivisions: 384,000 darts (thesis: 3,689 ms)."""
    def run():
        gm = subdivide.volume(build_fruit("round_tomato"), 2)
        return gm, gm.is_valid()

    seconds, (gm, valid) = _best(run, 5)
    return _record(seconds, 0.370, gm, valid, reference_seconds=3.689)


def bench_million_darts():
    """A fruit of 1,020,000 darts (precision 170, 100 branches per ring) built and validated."""
    def run():
        gm = build_fruit("round_tomato", precision=170, ph=100, nbvolangle=5)
        return gm, gm.is_valid()

    seconds, (gm, valid) = _best(run, 3)
    return {"seconds": round(seconds, 6), "target_seconds": 2.0, "ok": bool(valid and seconds <= 2.0),
            "darts": gm.n_darts, "volumes": gm.n_volumes, "valid": bool(valid)}


def bench_tomato_with_tissues():
    """Round tomato, two volume subdivisions, tissues and 120 rounded seeds (no thesis figure)."""
    def run():
        gm = build_fruit("round_tomato", volume_levels=2)
        return gm, gm.is_valid()

    seconds, (gm, valid) = _best(run, 3)
    return _record(seconds, 2.0, gm, valid)
