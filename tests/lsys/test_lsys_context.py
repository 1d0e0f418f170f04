"""Context matching for the whole string at once equals a simple module-by-module matcher."""

import numpy as np
import pytest

from ramure.lsys import LSystem
from ramure.lsys.engine._context_kernel import match_contexts
from ramure.lsys.engine.derive import bracket_matches, context_neighbours

OPEN, CLOSE = 0, 1


# -- the reference: Ramure 0.1's walks, one module at a time ----------------------
def walk_left(i, count, sym, match, ignore):
    out, j = [], i - 1
    while len(out) < count:
        if j < 0:
            return None
        s = sym[j]
        if s == CLOSE:
            if match[j] < 0:
                return None
            j = match[j] - 1
        elif s == OPEN or s in ignore:
            j -= 1
        else:
            out.append(j)
            j -= 1
    out.reverse()
    return out


def walk_right(i, count, sym, match, ignore):
    out, j = [], i + 1
    while len(out) < count:
        if j >= len(sym):
            return None
        s = sym[j]
        if s == OPEN:
            if match[j] < 0:
                return None
            j = match[j] + 1
        elif s == CLOSE:
            return None
        elif s in ignore:
            j += 1
        else:
            out.append(j)
            j += 1
    return out


def reference_match(sym, match, ignore, i, left, right, nparams=None):
    """``left``/``right``: wanted symbols in string order (-1 = any).  Context positions or None."""
    got_left = walk_left(i, len(left), sym, match, ignore)
    got_right = walk_right(i, len(right), sym, match, ignore)
    if got_left is None or got_right is None:
        return None
    got = got_left + got_right
    if all(w < 0 or sym[p] == w for p, w in zip(got, list(left) + list(right))):
        return got
    return None


def random_string(rng, n, balanced):
    sym, depth = [], 0
    for _ in range(n):
        r = rng.random()
        if r < 0.2:
            sym.append(OPEN)
            depth += 1
        elif r < 0.4 and (depth or not balanced):
            sym.append(CLOSE)
            depth = max(depth - 1, 0)
        else:
            sym.append(int(rng.integers(2, 6)))
    if balanced:
        sym += [CLOSE] * depth
    return np.array(sym, np.int32)


@pytest.mark.parametrize("seed", range(30))
def test_neighbours_equal_the_reference_walks(seed):
    rng = np.random.default_rng(seed)
    sym = random_string(rng, int(rng.integers(1, 300)), balanced=seed % 3 != 0)
    ignore = set(rng.choice([2, 3, 4, 5], size=int(rng.integers(0, 3)), replace=False).tolist())
    match = bracket_matches(sym, OPEN, CLOSE)
    prev, nxt = context_neighbours(sym, OPEN, CLOSE, ignore)
    for i in range(len(sym)):
        left = walk_left(i, 1, sym, match, ignore)
        right = walk_right(i, 1, sym, match, ignore)
        assert prev[i] == (left[0] if left else -1)
        assert nxt[i] == (right[0] if right else -1)


@pytest.mark.parametrize("seed", range(30))
def test_multi_module_and_wildcard_contexts_equal_the_reference(seed):
    rng = np.random.default_rng(100 + seed)
    sym = random_string(rng, int(rng.integers(20, 400)), balanced=seed % 4 != 0)
    ignore = {3} if seed % 2 else set()
    match = bracket_matches(sym, OPEN, CLOSE)
    prev, nxt = context_neighbours(sym, OPEN, CLOSE, ignore)
    nparams = np.zeros(len(sym), np.int8)
    cand = np.flatnonzero(sym >= 2)
    for _ in range(8):
        left = rng.integers(-1, 6, size=int(rng.integers(0, 3))).clip(-1, 5)
        left[left == OPEN] = 2
        left[left == CLOSE] = -1
        right = rng.integers(-1, 6, size=int(rng.integers(0, 3))).clip(-1, 5)
        right[right == OPEN] = 4
        right[right == CLOSE] = -1
        wanted = np.r_[left[::-1], right].astype(np.int64)
        sides = np.r_[-np.ones(len(left)), np.ones(len(right))].astype(np.int64)
        ok, found = match_contexts(cand, prev, nxt, sym, nparams, wanted, np.full(len(wanted), -1), sides)
        for c, i in enumerate(cand.tolist()):
            expected = reference_match(sym.tolist(), match, ignore, int(i), left.tolist(), right.tolist())
            assert ok[c] == (expected is not None)
            if expected is not None:  # found: left nearest first, then right
                assert found[:, c].tolist() == expected[: len(left)][::-1] + expected[len(left) :]


class ReferenceLSystem(LSystem):
    """An LSystem that matches contexts with the reference walks (slow, simple)."""

    fused_choice = False  # every group through _match_context, on long strings too

    def _match_context(self, group, cand, symbols, nparams, string, cache):
        match = bracket_matches(symbols, *self.bracket_ids)
        sym = symbols.tolist()
        left = [s for s, _ in group.left]
        right = [s for s, _ in group.right]
        global OPEN, CLOSE
        saved = OPEN, CLOSE
        OPEN, CLOSE = (-9 if b is None else b for b in self.bracket_ids)
        try:
            rows = [reference_match(sym, match, self.ignore_ids, int(i), left, right) for i in cand]
        finally:
            OPEN, CLOSE = saved
        ok = np.array(
            [r is not None and all(nparams[p] == a for p, (_, a) in zip(r, group.left + group.right)) for r in rows], bool
        )
        slots = [-k for k in range(1, len(left) + 1)] + list(range(1, len(right) + 1))
        found = {
            s: np.array([r[len(left) - (-s)] if s < 0 else r[len(left) + s - 1] for r, o in zip(rows, ok) if o], np.int64)
            for s in slots
        }
        cand = cand[ok]
        ctx = {s: string[v] if len(v) else np.zeros(0, np.int64) for s, v in found.items()}
        for r in group.rules:
            cache[r] = {"pos": cand, **ctx}
        return cand, ctx


CONTEXT_GRAMMARS = [
    "grammars/context_plant.lsys",
    """#ignore: + - F
n: 12
w: B[+A]F[-A]A
p:
  A < A -> A[+B]
  B < A > A -> B
  A B < A -> F
  A < B > F -> A
  B -> A
""",
    """n: 10
w: A(1)[B(2)]A(3)[A(4)[B(5)]]B(6)
p:
  A(x) < B(y) > A(z) -> B(x+z)A(y)
  B(y) < A(x) : x > 2 -> A(x-1)[B(y)]
  A(x) -> A(x+1)
  B(y) -> [A(y)]B(y+1)
""",
]


@pytest.mark.parametrize("source", CONTEXT_GRAMMARS)
def test_context_derivations_equal_the_reference_matcher(source):
    make = LSystem.from_file if source.endswith(".lsys") else LSystem.from_text
    fast = make(source)
    slow = ReferenceLSystem(fast.grammar)
    n = min(fast.n, 25)
    a, b = fast.derive(n=n), slow.derive(n=n)
    assert len(a) > 20
    assert a.to_string() == b.to_string()


def test_many_sibling_branches_match_like_the_reference():
    """`[A]` x k and `A[A]` chains: the memoised walk gives the reference's answer."""
    text = "n: 1\nw: " + "A[A]" * 300 + "[A]" * 300 + "\np:\n  A < A > A -> B\n  A < A -> C\n"
    fast = LSystem.from_text(text)
    assert fast.derive().to_string() == ReferenceLSystem(fast.grammar).derive().to_string()
    assert "C" in fast.derive().to_string()
