"""Exploration speed (issue 3): sweep + PCA + 27 picks, no thumbnails, on all cores.

Reference system (Salomon 2017, Table 5.3): 18 s for Honda sympodial's 486
variants, 65 s for Honda monopodial's 2,187, 199 s and 4.4 GB for 1,215
variants of a 16.8k-character grammar.  Targets here (2 cores): 486 in <= 3 s,
2,187 in <= 15 s, peak memory <= 1 GB.

Each run happens in a fresh Python process so the figures do not depend on
what ran before; ``seconds`` is the best of three ``explore()`` calls (sweep,
PCA with its first scikit-learn import, picks; cache off) and
``median_seconds`` their median; ``wall_seconds`` is the best run's whole
process, imports included.  ``derivations`` counts the distinct plants
actually derived (variants changing only constants their rule never reads
are the same plant; see :func:`ramure.metrics.variants.distinct_variants`).
``peak_mb`` bounds the peak memory of the run: the parent's peak RSS plus
``jobs`` times the largest worker's peak RSS (workers run at the same time;
shared pages are counted in each, so the real figure is lower).
"""

import json
import os
import subprocess
import sys
import time

_CHILD = r"""
import json, os, resource, sys, time
from ramure.lsys import LSystem
from ramure.metrics import explore
path, n, jobs = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
ls = LSystem.from_file(path)
t0 = time.perf_counter()
exp = explore(ls, n=n, n_jobs=jobs, cache=False)
seconds = time.perf_counter() - t0
me = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
kids = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
print(json.dumps({"seconds": seconds, "sweep_seconds": exp.sweep.seconds_, "variants": exp.sweep.n_variants_,
                  "derivations": exp.sweep.n_derived_,
                  "failed": int(exp.sweep.failed_.sum()), "segments": int(exp.sweep.base_metrics_[5]),
                  "string_chars": len(ls.derive(n=n).to_string()),
                  "parent_mb": me, "worker_mb": kids, "matching": exp.matching}))
"""


def _once(grammar, n, jobs, root):
    t0 = time.perf_counter()
    out = subprocess.run(
        [sys.executable, "-c", _CHILD, grammar, str(n), str(jobs)],
        cwd=root,
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "PYTHONPATH": root},
    )
    r = json.loads(out.stdout.strip().splitlines()[-1])
    r["wall"] = time.perf_counter() - t0
    return r


def _run(grammar, n, target_seconds, reference_seconds=None, target_mb=1024, repeat=3):
    """Best of ``repeat`` fresh processes (the machine is shared: the best run is the least disturbed)."""
    jobs = os.cpu_count() or 1
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    runs = [_once(grammar, n, jobs, root) for _ in range(repeat)]
    r = min(runs, key=lambda x: x["seconds"])
    wall = r["wall"]
    peak = max(x["parent_mb"] + jobs * x["worker_mb"] for x in runs)
    record = {
        "seconds": round(r["seconds"], 3),
        "target_seconds": target_seconds,
        "median_seconds": round(sorted(x["seconds"] for x in runs)[len(runs) // 2], 3),
        "wall_seconds": round(wall, 3),
        "sweep_seconds": round(r["sweep_seconds"], 3),
        "variants": r["variants"],
        "derivations": r["derivations"],
        "failed": r["failed"],
        "n": n,
        "jobs": jobs,
        "segments_per_variant": r["segments"],
        "string_chars": r["string_chars"],
        "variants_per_second": round(r["variants"] / r["seconds"], 1),
        "peak_mb": round(peak, 1),
        "target_peak_mb": target_mb,
        "matching_optimal": round(r["matching"]["optimal"], 3),
        "matching_greedy": round(r["matching"]["greedy"], 3),
        "matching_sequential": round(r["matching"]["sequential"], 3),
        "ok": r["seconds"] <= target_seconds and peak <= target_mb,
    }
    if reference_seconds:
        record["reference_seconds"] = reference_seconds
    return record


def bench_honda_sympodial_486_variants():
    return _run("grammars/honda_sympodial.lsys", 7, target_seconds=3.0, reference_seconds=18)


def bench_honda_monopodial_2187_variants():
    return _run("grammars/honda_monopodial.lsys", 7, target_seconds=15.0, reference_seconds=65)


def bench_ternary_branching_729_variants_30k_chars():
    # A string twice the 16.8k characters of the thesis's largest grammar (199 s, 4.4 GB there).
    return _run("grammars/ternary_branching.lsys", 6, target_seconds=15.0)


def bench_first_exploration_honda_n10():
    """Issue 16: the first exploration a qualifier needs (Honda sympodial n = 10, 486 variants,
    1,023 segments each, ten metrics and five shape metrics), fresh process, cache off."""
    return _run("grammars/honda_sympodial.lsys", 10, target_seconds=3.0)


_QUALIFY_CHILD = r"""
import json, sys, tempfile, time
import numpy as np
from ramure.lsys.regeneration.regen import Session
from ramure.metrics import explore
from ramure.metrics.apply import apply_qualifier
cache = tempfile.mkdtemp()
exp = explore("honda_sympodial", n=10, n_jobs=-1, cache_dir=cache)      # first exploration, then cached
exp = explore("honda_sympodial", n=10, n_jobs=-1, cache_dir=cache)
session = Session("honda_sympodial", n=10)
tree = session.tree
rng = np.random.default_rng(0)
f = set(session.leaves_with_symbol("F").tolist())
nodes = np.flatnonzero(tree.alive & (tree.child_count > 0) & (tree.depth >= 3))
times, improved = [], 0
apply_qualifier(session, "tall", exp.sweep, selection=[l for l in tree.leaves_under(int(nodes[0])).tolist() if l in f])
session.undo()
for q in ["dense", "tall", "upright", "thick", "wide", "regular", "small", "bushy", "symmetric", "drooping"]:
    sel = [l for l in tree.leaves_under(int(rng.choice(nodes))).tolist() if l in f]
    t0 = time.perf_counter()
    out = apply_qualifier(session, q, exp.sweep, selection=sel, points=exp.points)
    times.append(time.perf_counter() - t0)
    improved += out.improved
    if out.regen is not None:
        session.undo()
print(json.dumps({"times": times, "improved": improved, "cached": bool(exp.sweep.from_cache_)}))
"""


def bench_qualify_selection_honda_n10():
    """Issue 16: applying a qualifier to a selection, exploration cached (Honda n = 10): <= 300 ms.

    Ten qualifiers on ten random branches (3+ levels down); ``seconds`` is the
    median apply time (min-cut once per ascension level, regrow and measure
    each try, undo the rejected ones), ``max_seconds`` the slowest.
    """
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = subprocess.run(
        [sys.executable, "-c", _QUALIFY_CHILD],
        cwd=root,
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "PYTHONPATH": root},
    )
    r = json.loads(out.stdout.strip().splitlines()[-1])
    times = sorted(r["times"])
    median = times[len(times) // 2]
    return {
        "seconds": round(median, 4),
        "target_seconds": 0.3,
        "max_seconds": round(times[-1], 4),
        "min_seconds": round(times[0], 4),
        "applies": len(times),
        "improved": r["improved"],
        "exploration_cached": r["cached"],
        "ok": median <= 0.3,
    }
