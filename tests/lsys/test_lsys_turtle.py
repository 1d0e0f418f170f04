"""The compiled turtle equals Ramure's original Python turtle (tests/lsys/turtle_reference.py)."""

import numpy as np
import pytest

import ramure.grammars as grammar_files
from ramure.errors import DerivationError
from ramure.lsys import LSystem
from ramure.lsys.interpretation.turtle import SYMBOL_ACTIONS, TurtleAction, interpret, interpret_string

import turtle_reference

TOL = 1e-9
MAX_REFERENCE_MODULES = 60_000  # the reference runs ~0.5 M modules/s: keep each case short


def assert_same_skeleton(new, ref):
    """Positions, frames, widths, orders, colours, parents, leaf ids and organs agree."""
    assert len(new) == len(ref)
    for name in ("start", "end", "normal", "base_radius", "top_radius"):
        np.testing.assert_allclose(getattr(new, name), getattr(ref, name), rtol=0, atol=TOL, err_msg=name)
    for name in ("order", "leaf_id", "color", "parent"):
        np.testing.assert_array_equal(getattr(new, name), getattr(ref, name), err_msg=name)
    assert new.order.dtype == ref.order.dtype and new.leaf_id.dtype == ref.leaf_id.dtype
    a, b = new.organs, ref.organs
    assert len(a) == len(b)
    assert a.kind.tolist() == b.kind.tolist()
    np.testing.assert_array_equal(a.leaf_id, b.leaf_id)
    for name in ("position", "frame", "size"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=0, atol=TOL, err_msg=name)
    np.testing.assert_array_equal(a.params, b.params)
    if b.color is not None:
        np.testing.assert_array_equal(a.color, b.color)
    ref_polygons = ref.extra.get("polygons", [])
    assert len(new.polygons) == len(ref_polygons)
    if ref_polygons:
        np.testing.assert_array_equal(new.polygons.leaf_id, [q[0] for q in ref_polygons])
        np.testing.assert_array_equal(new.polygons.color, [q[1] for q in ref_polygons])
        np.testing.assert_array_equal(new.polygons.sizes, [len(q[2]) for q in ref_polygons])
        np.testing.assert_allclose(new.polygons.points, np.concatenate([q[2] for q in ref_polygons]), rtol=0, atol=TOL)


def _derive_small(ls, n):
    """Derive at ``n`` or fewer steps so the reference stays fast."""
    for steps in range(n, -1, -1):
        d = ls.derive(n=steps)
        if len(d) <= MAX_REFERENCE_MODULES:
            return d
    return d


@pytest.mark.parametrize("name", grammar_files.names())
def test_every_shipped_grammar_matches_the_reference(name):
    ls = LSystem.from_file(name)
    d = _derive_small(ls, ls.n)
    ref = turtle_reference.interpret(d)
    # the derived string itself (interpretation rules, which the reference does not know, aside)
    assert_same_skeleton(interpret_string(ls, d.tree, d.tree.leaves), ref)
    if name in ("honda_sympodial", "fruit_tree", "plant_1_24d"):
        assert len(ref) > 50 and (name != "fruit_tree" or len(ref.organs) > 10)  # not vacuous


ABOP_STYLE = {
    # ABOP fig. 2.8-like tree with tropism, $ and widths
    "tropism": """#define d1 94.74
#define d2 132.63
#define a 18.95
#define lr 1.109
#define vr 1.732
#tropism 0 0 -1 0.22
n: 6
w: !(1)F(200)/(45)A
p:
  A -> !(vr)F(50)[&(a)F(50)A]/(d1)[&(a)F(50)A]/(d2)[&(a)F(50)A]
  F(l) -> F(l*lr)
  !(w) -> !(w*vr)
""",
    "roll_horizontal": """n: 5
w: A
p:
  A -> F[+(30)$&(20)A][-(40)$^(10)A]\\(70)/(20)|F$A
""",
    "widths_colours": """#width 0.4
n: 5
w: A
p:
  A -> !F'[+!(0.2)'(3)A][-;A]!A
""",
    "organs": """#organ Bud Flower
n: 4
w: A
p:
  A -> F(0.8)[&(40)Leaf(0.3)][^(30)Fruit][+Bud(0.1)]/(137.5)Flower(0.5)f(0.2)A
""",
    "vertical_dollar": """n: 2
w: $F$[&(90)$F$]
p:
  F -> F$F
""",
}


@pytest.mark.parametrize("name", sorted(ABOP_STYLE))
def test_abop_style_grammars_match_the_reference(name):
    d = LSystem.from_text(ABOP_STYLE[name]).derive()
    ref = turtle_reference.interpret(d)
    assert len(ref) > 0
    assert_same_skeleton(interpret(d), ref)


SYMBOLS = [
    "F",
    "F(0.7)",
    "f",
    "f(0.3)",
    "+",
    "+(17)",
    "-",
    "-(33)",
    "&",
    "&(12)",
    "^",
    "^(71)",
    "\\",
    "\\(40)",
    "/",
    "/(140)",
    "|",
    "$",
    "!",
    "!(0.3)",
    "'",
    "'(4)",
    ";",
    "Leaf(0.5)",
    "Fruit",
    "A",
    "B",
    "C",
]


def random_grammar(rng):
    """A random bracketed turtle grammar, with tropism or not."""

    def word(k):
        out, depth = [], 0
        for _ in range(k):
            r = rng.random()
            if r < 0.12:
                out.append("[")
                depth += 1
            elif r < 0.22 and depth:
                out.append("]")
                depth -= 1
            else:
                out.append(SYMBOLS[rng.integers(len(SYMBOLS))])
        out += ["]"] * depth  # the grammar layer refuses unbalanced brackets
        return "".join(out)

    lines = [f"#angle {rng.uniform(5, 90):.3f}", f"n: {rng.integers(1, 4)}", f"w: {word(6)}A"]
    if rng.random() < 0.4:
        lines.insert(0, f"#tropism {rng.normal():.3f} {rng.normal():.3f} {rng.normal():.3f} {rng.uniform(0, 0.3):.3f}")
    lines += ["p:", f"  A -> {word(10)}A{word(4)}B", f"  B -> {word(8)}C", f"  C -> {word(6)}A"]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("seed", range(40))
def test_random_grammars_match_the_reference(seed):
    text = random_grammar(np.random.default_rng(seed))
    d = LSystem.from_text(text).derive()
    try:
        ref = turtle_reference.interpret(d)
    except DerivationError:
        with pytest.raises(DerivationError):
            interpret(d)
        return
    assert_same_skeleton(interpret(d), ref)


def test_actions_are_a_named_enum_covering_every_turtle_symbol():
    assert SYMBOL_ACTIONS["F"] is TurtleAction.DRAW and SYMBOL_ACTIONS["$"] is TurtleAction.ROLL_HORIZONTAL
    assert set(SYMBOL_ACTIONS) == set(turtle_reference._ACTIONS)
    assert {k: int(v) for k, v in SYMBOL_ACTIONS.items()} == turtle_reference._ACTIONS
    assert int(TurtleAction.ORGAN) == turtle_reference._ORGAN


def test_known_geometry_of_a_small_plant():
    """F[+F]F at 90 degrees: closed-form positions, parents, orders and tapering."""
    sk = LSystem.from_text("#angle 90\n#width 0.2\nn: 0\nw: F[+F]!(0.1)F\np:\n F -> F").derive().skeleton()
    np.testing.assert_allclose(sk.start, [[0, 0, 0], [0, 0, 1], [0, 0, 1]], atol=1e-12)
    np.testing.assert_allclose(sk.end, [[0, 0, 1], [-1, 0, 1], [0, 0, 2]], atol=1e-12)
    assert sk.parent.tolist() == [-1, 0, 0] and sk.order.tolist() == [0, 1, 0]
    np.testing.assert_allclose(sk.top_radius, [0.05, 0.1, 0.05])


def test_turtle_overflow_names_the_module():
    d = LSystem.from_text("n: 0\nw: F(1e308)F(1e308)\np:\n A -> A").derive()
    with pytest.raises(DerivationError, match="not finite"):
        interpret(d)
