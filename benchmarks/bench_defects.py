"""Fruit defects (issue 17) on the twice volume-subdivided round tomato.

The thesis (Table 2.26) builds this tomato (384,000 darts there; ~400,000 here with seeds) in
3,689 ms and gives no defect timings.  Target: each defect <= 40 ms.

Each defect runs 7 times on one fruit built outside the timing; the figures are medians.
``seconds`` is wall time, ``cpu_seconds`` the process's CPU time over the same calls (on a
machine shared with other jobs the wall time is inflated by waiting for a core; the CPU
time is what the defect costs).  ``ok`` judges the CPU median.  ``first_seconds`` is the
first defect on a freshly built fruit: it builds the map's topology index (vertex ids,
edges, face rings, orientation; see :func:`ramure.gmap.organs.defects.prepare`) once, which
every later defect on that fruit or its copies reuses; ``copy_seconds`` is the pure
function's copy of the input map, included in every figure.
"""

from __future__ import annotations

import statistics
import time

from ramure.gmap.organs import defects as D
from ramure.gmap.organs.fruit import build_fruit

TARGET = 0.040
RUNS = 7
_FRUIT = {}


def _fruit():
    if "gm" not in _FRUIT:
        _FRUIT["gm"] = build_fruit("round_tomato", volume_levels=2, seeds=40, seed=0)
    return _FRUIT["gm"]


def _timed(fn, runs=RUNS):
    wall, cpu = [], []
    for _ in range(runs):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return statistics.median(wall), statistics.median(cpu)


def _result(fn):
    fresh = build_fruit("round_tomato", volume_levels=2, seeds=40, seed=0)
    t0 = time.perf_counter()
    fn(fresh)
    first = time.perf_counter() - t0
    gm = _fruit()
    fn(gm)  # warm: index and compiled loops ready
    wall, cpu = _timed(lambda: fn(gm))
    copy_wall, _ = _timed(gm.copy)
    return {
        "seconds": round(wall, 4),
        "cpu_seconds": round(cpu, 4),
        "target_seconds": TARGET,
        "ok": cpu <= TARGET,
        "first_seconds": round(first, 3),
        "copy_seconds": round(copy_wall, 4),
        "darts": gm.n_darts,
        "volumes": gm.n_volumes,
    }


def bench_defect_shrink():
    return _result(lambda gm: D.shrink(gm, 0.1, steps=1))


def bench_defect_rot():
    return _result(lambda gm: D.rot(gm, seed=1))


def bench_defect_hail_5():
    return _result(lambda gm: D.hail(gm, count=5, depth_mm=(2.0, 6.0), seed=1))


def bench_defect_crack():
    return _result(lambda gm: D.crack(gm, "longitudinal", sector=3, rings=(3, 6), depth=2, width_mm=1.0, healed=1))


def bench_fruit_dataset_100():
    """``ramure fruit batch --count 100 --defects random --seed 0``: 100 tomatoes with tissues
    (one volume subdivision), 4 views with masks (3 renders each: picture, reference, ids), a
    cut picture, a VTU and labels each, COCO files, on a pool of 2 processes.  Target 20 s
    (10 s with the two pictures of issue 17; see bench_fruit_batch for the rate).
    ``cpu_per_core_seconds`` = CPU of this process and its workers / 2: the
    wall time on 2 idle cores, whatever the machine's load."""
    import resource
    import shutil
    import tempfile

    from ramure.app.fruit_dataset import make_dataset

    folder = tempfile.mkdtemp(prefix="ramure-dataset-")
    try:
        before = [resource.getrusage(w) for w in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)]
        t0 = time.perf_counter()
        summary = make_dataset(folder, count=100, seed=0, defects="random", workers=2)
        wall = time.perf_counter() - t0
        after = [resource.getrusage(w) for w in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)]
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    cpu = sum((a.ru_utime + a.ru_stime) - (b.ru_utime + b.ru_stime) for a, b in zip(after, before))
    return {
        "seconds": round(wall, 3),
        "cpu_per_core_seconds": round(cpu / 2, 3),
        "target_seconds": 20.0,
        "ok": cpu / 2 <= 20.0,
        "fruit": summary["count"],
        "marketable": summary["marketable"],
    }
