"""L-Py ``.lpy`` models (issue 36): each construct on a small file written here, the history
tree and a regrowth, the small PlantGL against values computed by hand, and the refusals."""

import math

import numpy as np
import pytest

from ramure.lsys import DerivationError, GrammarError, LSystem, Session, regenerate
from ramure.lsys.readers.lpy import LpyLSystem
from ramure.lsys.readers.lpy_plantgl import (
    BezierCurve2D,
    Color3,
    Material,
    Matrix3,
    NurbsCurve,
    NurbsCurve2D,
    Point3Array,
    Polyline2D,
    QuantisedFunction,
    Vector2,
    Vector3,
    angle,
    cross,
)
from ramure.lsys.readers.lpy_translate import LpyError, scan_modules

GROWTH = """\
from random import random
module Apex(age), Internode(length)
extern(growth=2.0)

Axiom: Apex(0)

derivation length: 3
production:

Apex(a) :
    nproduce Internode(growth)
    if a < 2:
        produce [+(30)Apex(a+1)]Apex(a+1)
    else:
        produce Apex(a+1)

Internode(l) < Internode(m) --> Internode(m+l)

interpretation:
Internode(l) --> F(l)

endlsystem
"""


def _lpy(text, tmp_path=None, name="model.lpy"):
    if tmp_path is None:
        return LpyLSystem(text, name)
    path = tmp_path / name
    path.write_text(text)
    return LSystem.from_file(path)


def test_a_model_with_declarations_bodies_contexts_and_interpretation(tmp_path):
    ls = _lpy(GROWTH, tmp_path)
    assert isinstance(ls, LpyLSystem) and ls.n == 3 and ls.constants == {"growth": 2.0}
    d = ls.derive()
    # the second trunk Internode has the first as left context (the branch is skipped): 2 + 2
    assert d.to_string() == (
        "Internode(2)[+(30)Internode(2)[+(30)Internode(2)Apex(3)]Internode(2)Apex(3)]"
        "Internode(4)[+(30)Internode(2)Apex(3)]Internode(2)Apex(3)"
    )
    sk = d.skeleton()  # drawn through the interpretation rule Internode(l) --> F(l)
    lengths = np.linalg.norm(sk.end - sk.start, axis=1)
    assert sorted(lengths.round(6).tolist()) == [2.0] * 6 + [4.0]
    assert sk.end[:, 2].max() == pytest.approx(8.0)  # trunk: 2 + 4 + 2
    assert set(sk.leaf_id.tolist()) <= set(d.leaves.tolist())  # leaf ids are the derivation's


def test_constants_override_extern_and_the_history_records_each_rule(tmp_path):
    ls = _lpy(GROWTH, tmp_path)
    d = ls.derive(constants={"growth": 1.5})
    assert d.to_string().startswith("Internode(1.5)[")
    tree = d.tree
    (root,) = np.flatnonzero(tree.parent[: tree.size] == -1)
    assert ls.module_text(tree, root) == "Apex(0)"
    kids = tree.children(root)
    assert [ls.module_text(tree, k) for k in kids] == ["Internode(1.5)", "[", "+(30)", "Apex(1)", "]", "Apex(1)"]
    assert (tree.step[kids] == 1).all() and (tree.rule[kids] == 0).all()
    with pytest.raises(GrammarError, match="unknown constant"):
        ls.derive(constants={"nope": 1})
    counted = LpyLSystem("extern(k=2)\nAxiom: A(*range(k))\n")  # an int stays an int when overridden
    assert counted.derive().to_string() == "A(0,1)" and counted.derive(constants={"k": 3}).to_string() == "A(0,1,2)"
    ls.constants["growth"] = 0.5  # what `ramure derive --set growth=0.5` does
    assert ls.derive(n=1).to_string() == "Internode(0.5)[+(30)Apex(1)]Apex(1)"


def test_regrow_a_subtree_of_an_lpy_model_round_trip(tmp_path):
    text = GROWTH.replace("    if a < 2:", "    if a < 2 and random() < 0.6:")
    ls = _lpy(text, tmp_path)
    d = ls.derive(seed=1)
    tree = d.tree
    apex = [int(v) for v in range(tree.size) if tree.step[v] == 1 and ls.symbols[tree.symbol[v]] == "Apex"]
    before = d.to_string()
    old = set(tree.subtree(apex[-1]).tolist()) - {apex[-1]}
    seen = set()
    for seed in range(8):
        regenerate(d, [apex[-1]], seed=seed)
        seen.add(d.to_string())
        new = set(tree.subtree(apex[-1]).tolist()) - {apex[-1]}
        assert not new & old and all(tree.alive[v] for v in new)
        prefix = before[: before.index("]") + 1]  # the other branch is untouched
        assert d.to_string().startswith(prefix.split("]")[0])
    assert len(seen) > 1  # the random rule draws anew
    # a deterministic model regrows to the very same string, with new history nodes
    det = _lpy(GROWTH, tmp_path, "det.lpy").derive()
    text0 = det.to_string()
    names = det.lsystem.symbols
    roots = [int(v) for v in range(det.tree.size) if det.tree.step[v] == 1 and names[det.tree.symbol[v]] == "Apex"]
    size = det.tree.size
    regenerate(det, roots[:1], seed=5)
    assert det.to_string() == text0 and det.tree.size > size
    # and through a Session (what the desktop and the CLI's regen use)
    session = Session(tmp_path / "det.lpy")
    result = session.regrow([int(session.derivation.leaves[-1])])
    assert result.added >= 1 and len(session.derivation) == len(det)
    session.save(tmp_path / "det.json")  # the edit log replays on the .lpy file
    again = Session.load(tmp_path / "det.json")
    assert isinstance(again.lsystem, LpyLSystem) and again.derivation.to_string() == session.derivation.to_string()


def test_hooks_groups_stop_and_iteration_numbers():
    text = """\
log = []
def Start():
    log.append("start")
def StartEach():
    log.append(getIterationNb())
    if getIterationNb() == 1:
        useGroup(1)
def EndEach(lstring):
    log.append(len(lstring))
    if getIterationNb() == 2:
        Stop()
def End():
    log.append("end")

Axiom: A
derivation length: 10
production:
A --> AB
group 1:
B --> C
endgroup
endlsystem
"""
    ls = LpyLSystem(text)
    d = ls.derive()
    # step 1: A -> AB (group 0); step 2: group 1 on, B -> C; step 3: then Stop()
    assert d.to_string() == "ABCC"
    assert d.n == 3
    assert ls.record(d.tree).ns["log"] == ["start", 0, 2, 1, 3, 2, 4, "end"]


def test_decomposition_with_maximum_depth_and_module_names():
    text = """\
module Stem, Leaf
Axiom: Stem(3)
derivation length: 1
production:
decomposition:
maximum depth: 2
Stem(n) :
    if n > 0:
        produce FStem(n-1)
endlsystem
"""
    d = LpyLSystem(text).derive(n=0)
    # depth 2: Stem(3) -> F Stem(2) -> F F Stem(1), no further; 'FStem' is F then Stem (declared)
    assert d.to_string() == "FFStem(1)"
    assert [m[0] for m in scan_modules("FStem(1)AB~leaf@Gs?P", {"Stem"})] == ["F", "Stem", "A", "B", "~leaf", "@Gs", "?P"]


def test_ignore_value_patterns_several_modules_new_context_and_axiom_body():
    text = """\
Axiom:
    for i in range(3):
        nproduce A(i)
    nproduce +B S
derivation length: 1
ignore: +
production:
A(0) --> X
A(x) + B --> C(x)
A(x) > B --> R(x)
A(x) --> D(x)
S --> T
T << B --> T
endlsystem
"""
    d = LpyLSystem(text).derive()
    # A(0) matches the value pattern; A(1) has A(2) to its right (not B); A(2)+B are rewritten together
    assert d.to_string() == "XD(1)C(2)T"
    text2 = "Axiom: S A A [A] A\nderivation length: 1\nproduction:\nS --> T\nT << A --> T\nendlsystem\n"
    assert LpyLSystem(text2).derive().to_string() == "TTT[T]T"  # '<<' reads what the step produced
    text3 = "Axiom: S A A\nderivation length: 1\nproduction:\nS --> T\nT << A :\n  if False:\n    produce X\nT << A --> T\n"
    assert LpyLSystem(text3).derive().to_string() == "TTT"  # a rule that does not apply leaves the next one its context


def test_right_contexts_with_branches():
    text = """\
Axiom: I(1) [I(2) X] I(3) [I(4)] I(5) A [B] [C D] E
derivation length: 1
production:
I(n) > [I(k)]I(q) --> J(n,k,q)
A > [C] E --> X
A > [B] E --> Y
endlsystem
"""
    # '[' enters the next branch, ']' skips the rest of it; other branches are skipped on the way
    assert LpyLSystem(text).derive().to_string() == "J(1,2,3)[I(2)X]J(3,4,5)[I(4)]I(5)Y[B][CD]E"


def test_backward_derivation_reads_the_new_right_context():
    text = """\
def Start():
    backward()
Axiom: S(1) S(1) [S(1) S(5)] S(1) S(7)
derivation length: 1
production:
S(a) >> S(b) --> S(a+b)
endlsystem
"""
    # from the right: 7 stays, 1+7, in the branch 5 stays and 1+5, then 1+8 (the branch skipped), 1+9
    assert LpyLSystem(text).derive().to_string() == "S(10)S(9)[S(6)S(5)]S(8)S(7)"
    forward = LpyLSystem(text.replace("    backward()", "    forward()")).derive().to_string()
    assert forward == "S(1)S(1)[S(1)S(5)]S(1)S(7)"  # forward, nothing is produced on the right yet


def test_query_modules_get_the_turtle_position():
    text = "Axiom: F(2) +(90) F(3) ?P(0) A\nderivation length: 1\nproduction:\n?P(p) A --> B(p.x, p.z)\nendlsystem\n"
    d = LpyLSystem(text).derive()
    # H starts up +z; '+(90)' turns about U=+y toward L... the position after F(2) +(90) F(3)
    (b,) = [m for m in d.modules if m[0] == "B"]
    assert abs(b[1][0]) == pytest.approx(3.0) and b[1][1] == pytest.approx(2.0)


def test_initialisation_section_materials_scalars_and_curves():
    text = """\
Axiom: A(f(0.5))
derivation length: 1
production:
A(x) --> B(x * rate)
endlsystem
###### INITIALISATION ######

__lpy_code_version__ = 1.1

def __initialiseContext__(context):
\timport openalea.plantgl.all as pgl
\tColor_2 = pgl.Material("Color_2" , ambient = (60,60,15) , diffuse = 3 , )
\tcontext.turtle.setMaterial(2,Color_2)
\tscalars = [('rate', 'Float', 2.0, 0.0, 10.0, 2)]
\tcontext["__scalars__"] = scalars
\tfor s in scalars:
\t\tif not s[1] == "Category" : context[s[0]] = s[2]
\tf = pgl.NurbsCurve2D(ctrlPointList = pgl.Point3Array([(0, 0, 1),(0.5, 1, 1),(1, 0, 1)]), degree = 2)
\tparameterset = [({'name': 'Panel 1', 'active': True}, [('Function', f)])]
\tcontext["__functions__"] = [('f', f)]
\tcontext["__parameterset__"] = parameterset
\tcontext["f"] = pgl.QuantisedFunction(f)
"""
    ls = LpyLSystem(text)
    assert ls.constants == {"rate": 2.0}
    assert ls.grammar.materials[2] == pytest.approx((180 / 255, 180 / 255, 45 / 255, 1.0))
    assert ls.derive().modules == [("B", (pytest.approx(1.0, abs=1e-3),))]  # f(0.5) = 0.5 (the apex), times 2
    assert ls.derive(constants={"rate": 3.0}).modules == [("B", (pytest.approx(1.5, abs=1e-3),))]


def test_small_plantgl_against_values_by_hand():
    a, b = Vector3(1, 0, 0), Vector3(0, 2, 0)
    assert list(a ^ b) == [0, 0, 2] and a * b == 0 and list(a + b * 2) == [1, 4, 0]
    c = Vector3(3, 4, 0)
    assert c.normalize() == 5 and list(c) == [0.6, 0.8, 0.0]
    # a clamped quadratic NURBS with 3 points is a Bezier: B(t) = (1-t)^2 P0 + 2t(1-t) P1 + t^2 P2
    pts = Point3Array([(0, 0, 1), (1, 2, 1), (3, 0, 1)])
    nurbs, bezier = NurbsCurve2D(pts, degree=2), BezierCurve2D(pts)
    for t in (0.0, 0.3, 0.5, 1.0):
        want = [(2 * t * (1 - t)) * 1 + t * t * 3, 2 * t * (1 - t) * 2]
        assert list(nurbs.getPointAt(t)) == pytest.approx(want)
        assert list(bezier.getPointAt(t)) == pytest.approx(want)
    # a weight pulls the curve: rational Bezier, w1 = 3 at t = 0.5: (0.25*0 + 0.5*3*P1 + 0.25*P2) / (0.25 + 1.5 + 0.25)
    heavy = BezierCurve2D(Point3Array([(0, 0, 1), (1, 2, 3), (3, 0, 1)]))
    assert list(heavy.getPointAt(0.5)) == pytest.approx([(1.5 + 0.75) / 2, 3 / 2])
    line = Polyline2D([(0, 0), (1, 1), (3, 1)])
    assert line.lastKnot == 2 and list(line.getPointAt(1.5)) == [2.0, 1.0]
    assert line.getLength() == pytest.approx(math.sqrt(2) + 2)
    f = QuantisedFunction(line)
    assert f(0.5) == pytest.approx(0.5) and f(2.0) == pytest.approx(1.0)
    assert list(NurbsCurve([(0, 0, 0, 1), (1, 2, 1, 1), (3, 0, 2, 1)], degree=2).getPointAt(0.5)) == [1.25, 1, 1]
    to_u = Polyline2D([(0, 0), (1, 0), (3, 0)]).getArcLengthToUMapping()
    assert to_u(0.5) == pytest.approx(1.25) and to_u(1 / 6) == pytest.approx(0.5)  # half of 3 is 1.5 along
    assert angle(Vector2(1, 0), Vector2(0, -2)) == pytest.approx(-math.pi / 2)  # signed in 2D
    assert angle(Vector3(1, 0, 0), Vector3(0, 0, -2)) == pytest.approx(math.pi / 2)
    assert cross((1, 2), (3, 4)) == -2.0
    assert angle(Vector3(0, 1, 0), Vector3(0, 0, 1), Vector3(-1, 0, 0)) == pytest.approx(-math.pi / 2)
    turn = Matrix3.axisRotation((1, 0, 0), math.pi / 2)  # y turns to z about x
    assert list(turn * Vector3(0, 1, 0)) == pytest.approx([0, 0, 1])
    assert list((turn * turn) * Vector3(0, 1, 0)) == pytest.approx([0, -1, 0])
    assert QuantisedFunction([(0, 1), (1, 3)])(0.25) == pytest.approx(1.5)
    assert Material("m", ambient=(100, 50, 0), diffuse=2).rgba() == pytest.approx((200 / 255, 100 / 255, 0, 1))
    assert Color3(1, 2, 3).rgb01() == pytest.approx((1 / 255, 2 / 255, 3 / 255))


@pytest.mark.parametrize(
    "text, line, words",
    [
        ("lpyimport other\nAxiom: A\n", 1, "lpyimport"),
        ("Axiom: A\nproduction:\nA >> x([B]) --> C\nendlsystem\n", 3, "repeated pattern x(...)"),
        ("Axiom: A\nproduction:\n[B] < A --> C\nendlsystem\n", 3, "bracket in a rule's left context"),
        ("Axiom: A\nproduction:\nA --> B(1\nendlsystem\n", 3, "unclosed"),
        ("Axiom: A\nproduction:\nA(x+1) --> B\nendlsystem\n", 3, "a name or a value"),
        ("from openalea.plantgl.all import Text\nAxiom: A\n", 1, "openalea.plantgl.all.Text"),
        ("x = 1\n\nAxiom: A(undefined_name)\n", 3, "undefined_name"),
        ("Axiom: A\nderivation length: 1\nproduction:\nA :\n    produce B(1/0)\nendlsystem\n", 5, "ZeroDivisionError"),
        ("Axiom: A\nproduction:\nA :\n  if x\nendlsystem\n", 4, "Python syntax"),
        ("Axiom: A\nderivation length: 1\nproduction:\nA :\n  return [1]\nendlsystem\n", 4, "not a module"),
    ],
)
def test_unsupported_or_broken_files_are_refused_at_their_line(text, line, words):
    with pytest.raises(GrammarError) as err:
        LpyLSystem(text, "bad.lpy").derive()
    assert err.value.line == line and words in str(err.value)
    assert isinstance(err.value, (LpyError, DerivationError))


def test_ramure_derive_reads_an_lpy_file(tmp_path, capsys):
    from ramure.app.cli import main

    path = tmp_path / "m.lpy"
    path.write_text(GROWTH)
    assert main(["derive", str(path), "-n", "1"]) == 0
    assert capsys.readouterr().out.strip() == "Internode(2)[+(30)Apex(1)]Apex(1)"
    path.write_text("Axiom: A\nproduction:\nA >> x([B]) --> D\nendlsystem\n")
    assert main(["derive", str(path)]) == 2
    assert "line 3" in capsys.readouterr().err


def test_ramure_check_counts_an_lpy_files_rules(tmp_path, capsys):
    from ramure.app.cli import main

    path = tmp_path / "m.lpy"
    path.write_text(
        "extern(k=2)\nAxiom: A(1)B\nderivation length: 2\nproduction:\nA(x) --> F(x)A(x+1)\nB --> C\n"
        "decomposition:\nC --> F\ninterpretation:\nA --> F\nendlsystem\n"
    )
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "ok — 2 rule(s) (and 1 decomposition, 1 interpretation), 1 constant(s), n = 2" in out
    assert out.split("\n")[0].endswith("axiom A(1)B")


def test_parameter_sets_carry_named_values_through_rules_and_drawing():
    from ramure.lsys.readers.lpy import LpyLSystem

    text = (
        "Axiom: I(ParameterSet(diameter=0.5, length=2))\nderivation length: 2\nproduction:\nI(p) :\n"
        "  q = p.copy()\n  q.length = p.length / 2\n  produce I(q) I(q)\ninterpretation:\n"
        "I(p) --> _(p.diameter) F(p.length)\nendlsystem\n"
    )
    d = LpyLSystem(text).derive()
    sk = d.skeleton()
    assert len(d) == 4 and np.allclose(sk.length, [0.5] * 4)  # 2 halved twice, four pieces
    plain = LpyLSystem("Axiom: _(0.5) F(0.5)\nderivation length: 0\nendlsystem\n").derive().skeleton()
    assert np.allclose(sk.base_radius, plain.base_radius[0])  # the diameter read from the set
