"""The cut preview on a big plant (issue 34): what it adds to the cut it shows."""

import time

import numpy as np

from ramure.app.model import Explorer


def bench_preview_1000_leaves_honda_n17():
    """Honda sympodial n = 17 (1.44 M modules), 1000 picked segments: the preview's own work
    (the regrown leaves from the roots' string spans, the climb, the stranded leaves) on top
    of the cut, whose time is the cut's benchmark's (bench_regen)."""
    ex = Explorer("grammars/honda_sympodial.lsys", n=17)
    segments = ex.skeleton.leaf_id
    ex.select(np.random.default_rng(1).choice(segments, 1000, replace=False))
    t0 = time.perf_counter()
    ex.plan()  # the cut, cached for this selection
    cut = time.perf_counter() - t0
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        preview = ex.preview()
        best = min(best, time.perf_counter() - t0)
    return {
        "seconds": round(best, 4),
        "cut_seconds": round(cut, 3),
        "target_seconds": 0.2,
        "ok": best <= 0.2,
        "modules": preview.total,
        "will_change": preview.changed,
        "message": preview.message[:80],
    }
