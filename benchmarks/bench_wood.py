"""Volumetric wood benchmarks (issue 13, spec decision 10).

Reference model: a 16-sided trunk, 10 years (20 half-year steps), 3 branches.
The thesis reports about 5 s on a Pentium IV 2.66 GHz for its trunk with
branches, with no size stated.  Targets: growth with the embedding every step
plus validity and chi checks <= 0.5 s; a cut picture <= 33 ms after the first
conversion; ``cut_map`` <= 100 ms (when the kernel has it); a 30-year trunk
with 20 branches <= 2 s and <= 800 MB (issue 39; issue 13 asked 5 s and 2 GB).
Medians of a few runs; the machine is shared, so figures move with the load.
"""

from __future__ import annotations

import os
import resource
import statistics
import sys
import time

import numpy as np

from ramure.gmap.organs import wood as W
from ramure.gmap.kernel.topology import assert_solid


_CPU = []  # CPU seconds of the last _median's runs (the machine is shared: wall moves with load)


def _median(fn, repeats=3):
    times, cpu, result = [], [], None
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        result = fn()
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    _CPU[:] = [statistics.median(cpu)]
    return statistics.median(times), result


def _record(seconds, target, gm, **extra):
    rec = {
        "seconds": round(seconds, 4),
        "target_seconds": target,
        "ok": bool(seconds <= target),
        "darts": gm.n_darts,
        "volumes": gm.n_volumes,
        "darts_per_second": round(gm.n_darts / seconds),
        **extra,
    }
    if _CPU:
        rec["cpu_seconds"] = round(_CPU[0], 4)
    rec["load_average"] = round(os.getloadavg()[0], 2)  # the machine is shared: read wall with this
    cpu = f", {rec['cpu_seconds']:.3f} s CPU" if "cpu_seconds" in rec else ""
    print(
        f"{gm.n_darts:,} darts in {seconds:.3f} s wall{cpu}: {gm.n_darts / seconds:,.0f} darts/s (load {rec['load_average']})",
        file=sys.stderr,
    )
    return rec


def bench_wood_reference_growth():
    """16-sided trunk, 10 years, 3 branches: growth, embedding, validity and chi every step."""
    seconds, w = _median(
        lambda: W.grow_wood("pine", years=10, branches=3, embed_every_step=True, check_every_step=True), repeats=5
    )
    cpu = _CPU[0]
    grow_only, _ = _median(lambda: W.grow_wood("pine", years=10, branches=3))
    _CPU[:] = [cpu]
    return _record(seconds, 0.5, w.gm, growth_only_seconds=round(grow_only, 4))


def bench_wood_cut_picture():
    """A z cut of the reference wood (VTK clip of the converted grid), after the first conversion."""
    w = W.grow_wood("pine", years=10, branches=3)
    t0 = time.perf_counter()
    grid = W.to_grid(w)
    convert = time.perf_counter() - t0

    def cut():
        return grid.clip(normal=(0, 0, 1), origin=(0, 0, 1.0), invert=True)

    seconds, part = _median(cut, repeats=7)
    return _record(seconds, 0.033, w.gm, conversion_seconds=round(convert, 4), cut_cells=part.n_cells)


def bench_wood_cut_map():
    """``cut_map`` (a 3G-map cut, from the kernel) of the reference wood, when available."""
    w = W.grow_wood("pine", years=10, branches=3)
    try:
        from ramure.gmap.kernel.cut import cut_map
    except ImportError:
        return {
            "seconds": None,
            "target_seconds": 0.1,
            "ok": False,
            "skipped": "kernel has no cut_map yet",
            "darts": w.gm.n_darts,
        }
    seconds, part = _median(lambda: cut_map(w.gm, (0, 0, 1), (0, 0, 1.0)))
    return _record(seconds, 0.1, w.gm, kept_darts=part.n_darts)


def bench_wood_30_years_20_branches():
    """A 30-year trunk with 20 branches, grown and embedded: <= 2 s and <= 800 MB (issue 39; one check after, timed apart).

    2,820,624 darts.  Issue 39 found 3.5 s and 1,035 MB; then 2.36 s and 802 MB.  The kernel's
    orbit labels then stopped copying alpha into int64, the embedding its per-dart corner sizes,
    orbits_from its numpy rings: on the shared 2-core machine (CPU seconds, 7 runs paired with
    the code before, medians) growth 1.85 -> 1.36 s, the check 0.67 -> 0.19 s, peak RSS
    801 -> 609 MB; ``benchmarks/wood_digest.py`` shows the maps unchanged.  Levels glued by
    year, dead stubs capped and branches of every order then added work and 14,336 darts; the
    corner gathers stopped buffering (``np.take(mode="clip")``).  Timed after a 3-year wood has
    loaded the compiled kernels (``bench_first_call`` times that load): quiet, 7 processes,
    growth 1.45-1.92 s, median 1.60 s; 576 MiB.  Then cells kept the right way out (the
    unfolding pull and checks of issue 39) and dead bark kept: whole process against the code
    before, 5 pairs in turn, wall ratio 1.02, peak 662 MiB; growth here, 7 processes on a machine
    slower that day (the code before grew in 1.56-2.47 s in the same hour): 1.71-2.99 s, median
    1.95 s, 661-663 MB.
    """
    W.grow_wood("pine", years=3, branches=2)  # warm: the kernels load from numba's cache once a process
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    _CPU.clear()
    t0, c0 = time.perf_counter(), time.process_time()
    w = W.grow_wood("pine", years=30, branches=20)
    seconds = time.perf_counter() - t0
    cpu = time.process_time() - c0
    t1 = time.perf_counter()
    assert_solid(w.gm)
    check = time.perf_counter() - t1
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    rec = _record(
        seconds,
        2.0,
        w.gm,
        peak_rss_mb=round(peak_mb),
        rss_before_mb=round(before / 1024),
        cpu_seconds=round(cpu, 3),
        check_seconds=round(check, 3),
    )
    rec["target_peak_rss_mb"] = 800
    rec["ok"] = bool(rec["ok"] and peak_mb <= 800)
    return rec


def bench_wood_g3l_grammars():
    """The shipped 3Gmap L-systems (trunk 8 steps, spiral 6, skeleton 5), parsed once, derived with seed 3.

    Before issue 37 (expressions through Python ``eval``, one volume at a time) the trunk took
    1.22 s CPU on the shared 2-core machine, 0.83 s after (compiled once, evaluated for all
    matching volumes at once); issue 39 asks for 20 times faster later.
    """
    from ramure.gmap.lsystem.engine import G3LSystem

    systems = [(G3LSystem.from_file(f"wood/{name}"), n) for name, n in (("trunk", 8), ("spiral", 6), ("skeleton", 5))]

    def run():
        return [s.derive(n, seed=3) for s, n in systems]

    seconds, out = _median(run)
    trunk = out[0]
    return _record(seconds, 1.5, trunk.gm, steps=8, all_three_darts=sum(d.gm.n_darts for d in out))


def bench_wood_g3l_trunk_20():
    """Issue 39: the ``.g3l`` trunk at n = 20 (161,664 darts) in at most 1.5 s, at least 100k darts/s.

    Before: 34 s (4.8k darts/s) at issue 39's filing, 8-9 s after issue 37's compiled
    expressions; then contexts, support faces and joins are found for all volumes of a rule
    at once instead of one volume at a time (each search scanned the whole map).
    """
    from ramure.gmap.lsystem.engine import G3LSystem

    trunk = G3LSystem.from_file("wood/trunk")
    seconds, out = _median(lambda: trunk.derive(20, seed=3), repeats=3)
    rec = _record(seconds, 1.5, out.gm, steps=20, target_darts_per_second=100_000)
    rec["ok"] = bool(rec["ok"] and rec["darts_per_second"] >= 100_000)
    return rec


if __name__ == "__main__":
    for name, fn in sorted(globals().items()):
        if name.startswith("bench_"):
            print(name, fn())
            np.random.seed(0)
