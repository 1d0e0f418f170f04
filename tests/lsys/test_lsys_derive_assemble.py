"""One derivation step assembled in one block (numpy and compiled paths) gives the history
tree the per-rule appends gave: every array equal, node ids included."""

import numpy as np
import pytest

from ramure.errors import RamureError
from ramure.lsys import LSystem
from ramure.lsys.engine._context_kernel import neighbours, reach
from ramure.lsys.engine.derive import bracket_matches
from tests.hardening.fuzz import aware

FIELDS = ("symbol", "nparams", "parent", "step", "rule", "index_in_rule", "child_start", "child_count", "alive")


class ReferenceAssembly(LSystem):
    """The per-rule assembly of Ramure 0.1 (one tree append per rule), kept as the reference."""

    fused_choice = False

    def _assemble(self, tree, string, chosen, step, rng, constants, rule_constants, context):
        lengths = np.ones(len(string), np.int64)
        active = [r for r in np.unique(chosen) if r >= 0]
        positions = {r: np.flatnonzero(chosen == r) for r in active}
        for r in active:
            lengths[positions[r]] = len(self._rules[r].succ_symbols)
        ends = np.cumsum(lengths)
        offsets = ends - lengths
        out = np.empty(int(ends[-1]) if len(ends) else 0, np.int64)
        keep = chosen < 0
        out[offsets[keep]] = string[keep]
        for r in active:
            crule, pos = self._rules[r], positions[r]
            k, m = len(crule.succ_symbols), pos.size
            parents = string[pos]
            if k == 0:
                tree.set_children(parents, -1, 0)
                continue
            ctx = context.get(r)
            ctx_nodes = None
            if ctx is not None:
                ctx_nodes = {s: v[np.searchsorted(ctx["pos"], pos)] for s, v in ctx.items() if s != "pos"}
            V = self._variables(crule, pos, ctx_nodes, tree, string)
            block = np.full((m, k, tree.max_params), np.nan)
            for j, args in enumerate(crule.succ_args):
                for a, fn in enumerate(args):
                    block[:, j, a] = self._evaluate(fn, V, r, rule_constants, constants, rng, m, tree, string, pos, "successor")
            ids = tree.append(
                np.tile(crule.succ_symbols, m),
                np.tile(crule.succ_nparams, m),
                block.reshape(m * k, -1),
                np.repeat(parents, k),
                step,
                r,
                np.tile(np.arange(k), m),
            )
            tree.set_children(parents, ids[0] + np.arange(m) * k, k)
            out[(offsets[pos][:, None] + np.arange(k)).ravel()] = ids
        return out


def _paths(text_or_name):
    """The same grammar three ways: reference, numpy-only, compiled kernels from the first step."""
    make = LSystem.from_text if "\n" in text_or_name else LSystem.from_file
    fast = make(text_or_name)
    fast.kernel_min_modules = 0
    numpy_only = LSystem(fast.grammar)
    numpy_only.kernel_min_modules = numpy_only.kernel_loaded_min_modules = 10**12
    return ReferenceAssembly(fast.grammar), numpy_only, fast


def assert_same_tree(a, b):
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a.tree, name), getattr(b.tree, name), err_msg=name)
    np.testing.assert_array_equal(a.tree.params, b.tree.params)
    np.testing.assert_array_equal(a.tree.leaves, b.tree.leaves)


STOCHASTIC = """#define r 0.6
n: 7
w: A(1)
p:
  A(x) : x < 4 -> F(uniform(0.5, 1.5))[+(normal(30, 5))A(x+1)]A(x+1)
  A(x) -> B(x)
  .3 B(x) -> F(x)B(x*r)
  .5 B(x) -> [-B(x)]B(x)
  .2 B(x) -> *
  F(l) -> F(l*1.01)
"""

CONTEXT_PARAMS = """#ignore: F
n: 9
w: A(1)[B(2)]A(3)F[A(4)[B(5)]]B(6)
p:
  A(x) < B(y) > A(z) -> B(x+z)A(y)
  B(y) < A(x) : x > 2 -> A(x-1)[B(y)]
  A(x) < A(y) -> A(x+y)F
  A(x) -> A(x+1)
  B(y) -> [A(y)]B(y+1)
"""


@pytest.mark.parametrize(
    "source, n",
    [
        ("context_plant", 30),
        ("honda_sympodial", 9),
        ("fruit_tree", 6),
        (STOCHASTIC, 7),
        (CONTEXT_PARAMS, 9),
        ("abop/bush_1_25", 5),
    ],
)
def test_block_assembly_equals_the_per_rule_reference(source, n):
    reference, numpy_only, fast = _paths(source)
    for seed in (0, 5):
        a = reference.derive(n=n, seed=seed)
        assert len(a) > 20
        assert_same_tree(a, numpy_only.derive(n=n, seed=seed))
        assert_same_tree(a, fast.derive(n=n, seed=seed))


def test_random_grammars_assemble_like_the_reference():
    rng = np.random.default_rng(41)
    compared = 0
    for _ in range(120):
        text = aware(rng)
        try:
            reference, numpy_only, fast = _paths(text)
            a = reference.derive(n=min(reference.n, 5))
        except RamureError:
            continue
        except RecursionError:
            continue
        assert_same_tree(a, numpy_only.derive(n=min(reference.n, 5)))
        assert_same_tree(a, fast.derive(n=min(reference.n, 5)))
        compared += 1
    assert compared > 40


def test_a_refused_step_leaves_the_tree_as_it_was():
    """A successor that fails to evaluate is refused before anything is appended."""
    ls = LSystem.from_text("n: 2\nw: A(2)\np:\n A(x) -> A(x-1)B(1/x)\n B(y) -> B(y)C\n")
    ls.kernel_min_modules = 0
    d = ls.derive()
    tree, size = d.tree, d.tree.size
    children = tree.child_count.copy()
    with pytest.raises(RamureError, match="division by zero"):
        ls.rewrite(tree, tree.leaves, 3, np.random.default_rng(0), ls.constants)
    assert tree.size == size
    np.testing.assert_array_equal(tree.child_count, children)


def test_reach_gives_the_neighbours_on_random_bracketed_strings():
    rng = np.random.default_rng(3)
    for _ in range(200):
        sym = rng.integers(0, 6, size=int(rng.integers(1, 60))).astype(np.int64)  # 0 = [, 1 = ], unbalanced too
        ignored = np.zeros(6, bool)
        ignored[rng.choice(6, size=2, replace=False)] = True
        prev, nxt = neighbours(sym, bracket_matches(sym, 0, 1), 0, 1, ignored)
        left, right = reach(sym, 0, 1, ignored)
        n = len(sym)
        assert prev.tolist() == [int(left[i - 1]) if i > 0 else -1 for i in range(n)]
        assert nxt.tolist() == [int(right[i + 1]) if i < n - 1 else -1 for i in range(n)]


def test_an_empty_successor_beside_parametric_rules_erases_its_module():
    # Found by the grammar fuzz: the erasing rule's zero-width block could not be reshaped.
    from ramure.lsys import LSystem

    d = LSystem.from_text("n: 2\nw: A(1,10)\np:\n  A(l,w) -> F(l)[B(l,w)]A(l*2,w)\n  B(l,w) ->\n").derive()
    assert d.to_string() == "F(1)[]F(2)[B(2,10)]A(4,10)"
