"""Selection and regeneration speed (issue 8)."""

import time

import numpy as np
from networkx.algorithms import flow

from ramure.lsys import LSystem
from ramure.lsys.regeneration.mincut import select_roots
from ramure.lsys.regeneration.regen import Session


def bench_cut_and_regrow_10_leaves_honda_n10():
    session = Session("grammars/honda_sympodial.lsys", n=10)
    rng = np.random.default_rng(0)
    best = float("inf")
    for i in range(7):
        sel = rng.choice(session.leaves_with_symbol("F"), 10, replace=False)
        t0 = time.perf_counter()
        result = session.regrow(sel, constants={"a2": 40 + i})
        best = min(best, time.perf_counter() - t0)
        session.undo()
    return {
        "seconds": round(best, 4),
        "target_seconds": 0.03,
        "ok": best <= 0.03,
        "roots": len(result.roots),
        "replaced_modules": result.removed,
    }


def _big_cut(flow_func):
    d = LSystem.from_file("grammars/honda_sympodial.lsys").derive(n=17)
    tree = d.tree
    tree.leaf_spans(), tree.depth  # per-derivation caches, shared by every later cut
    from ramure.lsys.regeneration.mincut import initial_capacities

    initial_capacities(tree)
    sel = np.random.default_rng(1).choice(tree.leaves, 1000, replace=False)
    t0 = time.perf_counter()
    cut = select_roots(tree, sel, n=17, flow_func=flow_func)
    return time.perf_counter() - t0, len(d), cut


def bench_mincut_1000_leaves_on_1M_modules_boykov_kolmogorov():
    seconds, modules, cut = _big_cut(flow.boykov_kolmogorov)
    return {
        "seconds": round(seconds, 3),
        "target_seconds": 1.0,
        "ok": seconds <= 1.0,
        "modules": modules,
        "graph_nodes": cut.graph.number_of_nodes(),
        "roots": len(cut.roots),
    }


def bench_mincut_1000_leaves_on_1M_modules_preflow_push():
    seconds, modules, cut = _big_cut(flow.preflow_push)
    return {
        "seconds": round(seconds, 3),
        "target_seconds": 1.0,
        "ok": seconds <= 1.0,
        "modules": modules,
        "graph_nodes": cut.graph.number_of_nodes(),
        "roots": len(cut.roots),
    }


def bench_mincut_1000_leaves_on_1M_modules_tree_recursion():
    """The default cut (the tree's own recursion, no max flow, no networkx): the same cut."""
    seconds, modules, cut = _big_cut(None)
    _, _, solved = _big_cut(flow.preflow_push)
    same = cut.cut_edges == solved.cut_edges and cut.roots.tolist() == solved.roots.tolist()
    return {
        "seconds": round(seconds, 3),
        "target_seconds": 1.0,
        "ok": seconds <= 1.0 and same,
        "same_cut_as_preflow_push": same,
        "modules": modules,
        "roots": len(cut.roots),
    }
