"""Leaf ageing and fall (issue 18) against the thesis's Table 4.1 (Desbenoit 2006).

Table 4.1: 9,142 leaves on two trees, 16 steps, 140.76 s cumulative (ageing plus the fall of
the leaves' bounding cylinders; hardware not stated). Targets here: the same size <= 14 s, aim
<= 2 s; ageing alone of 25,202 leaves (Fig. 4.15) for 16 steps <= 0.1 s.
"""

from __future__ import annotations


import numpy as np

import time

from ramure.lsys import LSystem
from ramure.lsys.architecture.seasons import age_leaves, age_states, autumn_chain
from benchtools import best

# Honda's sympodial tree with a leaf on every twig: 2^13 = 8,192 leaves at n = 13, plus the
# leaves of the last twigs' neighbours; close to the thesis's 9,142.
LEAFY = """
#define r1 0.9
#define r2 0.7
#define a1 10
#define a2 60
#define wr 0.707
#widthscale 0.02
n: 13
w: A(1,10)
p:
  A(l,w) -> !(w)F(l)[&(a1)B(l*r1,w*wr)]/(180)[&(a2)B(l*r2,w*wr)]
  B(l,w) -> !(w)F(l)[+(a1)$B(l*r1,w*wr)][-(a2)$B(l*r2,w*wr)][&(40)Leaf(0.3)]
"""


def bench_autumn_table_4_1():
    organs = LSystem.from_text(LEAFY).derive().skeleton().organs
    chain = autumn_chain()
    seconds, season = best(lambda: age_leaves(organs, chain, steps=16, seed=0, wind=(0.05, 0.02)))
    facts = season.facts(chain)
    cpu = _cpu(lambda: age_leaves(organs, chain, steps=16, seed=0, wind=(0.05, 0.02)), repeats=3)
    return {
        "seconds": round(seconds, 4),
        "cpu_seconds": round(cpu, 4),
        "target_seconds": 14.0,
        "aim_seconds": 2.0,
        "ok": seconds <= 14.0,
        "leaves": facts["leaves"],
        "fallen_leaves": facts["fallen_leaves"],
        "intersection_tests": facts["intersection_tests"],
        "trajectory_segments": facts["trajectory_segments"],
        "thesis_seconds": 140.76,
    }


def bench_ageing_25202_leaves():
    n = 25_202
    ids = np.arange(n)
    rng = np.random.default_rng(0)
    heat, humidity = rng.uniform(0, 1, n), rng.uniform(0, 1, n)
    chain = autumn_chain()
    seconds, _ = best(lambda: age_states(ids, heat, humidity, chain, 16, seed=0), repeats=5)
    return {
        "seconds": round(seconds, 4),
        "cpu_seconds": round(_cpu(lambda: age_states(ids, heat, humidity, chain, 16, seed=0)), 4),
        "target_seconds": 0.1,
        "ok": seconds <= 0.1,
        "leaves": n,
        "steps": 16,
    }


def _cpu(fn, repeats: int = 5) -> float:
    """Least process CPU time of ``fn()``: on a shared machine the wall time measures the load."""
    out = float("inf")
    for _ in range(repeats):
        c0 = time.process_time()
        fn()
        out = min(out, time.process_time() - c0)
    return out
