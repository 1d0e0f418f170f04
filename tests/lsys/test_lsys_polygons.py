"""Polygons { . }, their triangles, and what they carry (issue 15, part A)."""

import math

import numpy as np
import pytest

from ramure.errors import DerivationError, GrammarError
from ramure.lsys import LSystem
from ramure.lsys.interpretation.polygons import Polygons, triangle_areas, triangulate
from ramure.lsys.regeneration.regen import Session

S18, C18 = math.sin(math.radians(18)), math.cos(math.radians(18))

# ABOP fig. 1.26 (p. 25): a plant with leaves and flowers; ‘ is written '.
FIG_1_26 = """#module plant internode seg leaf flower pedicel wedge
#angle 18
n: 5
w: plant
p:
  plant -> internode+[plant+flower]--//[--leaf]internode[++leaf]-[plantflower]++plantflower
  internode -> Fseg[//&&leaf][//^^leaf]Fseg
  seg -> segFseg
  leaf -> ['{+f-ff-f+|+f-ff-f}]
  flower -> [&&&pedicel'/wedge////wedge////wedge////wedge////wedge]
  pedicel -> FF
  wedge -> ['^F][{&&&&-f+f|-f+f}]
"""


def polygon(points):
    pts = np.asarray(points, float)
    if pts.shape[1] == 2:
        pts = np.column_stack([pts, np.zeros(len(pts))])
    return pts, np.array([0, len(pts)])


def area_and_count(points):
    pts, offsets = polygon(points)
    tris, owner = triangulate(pts, offsets)
    return float(triangle_areas(pts, tris).sum()), len(tris), tris


def shoelace(points):
    p = np.asarray(points, float)
    x, y = p[:, 0], p[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


STAR = [
    (
        math.cos(math.radians(90 + 36 * k)) * (1.0 if k % 2 == 0 else 0.4),
        math.sin(math.radians(90 + 36 * k)) * (1.0 if k % 2 == 0 else 0.4),
    )
    for k in range(10)
]


@pytest.mark.parametrize(
    "points, area, triangles",
    [
        ([(0, 0), (1, 0), (1, 1), (0, 1)], 1.0, 2),  # unit square
        ([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], 3.0, 4),  # L-shape: three unit squares
        (STAR, 5 * 1.0 * 0.4 * math.sin(math.radians(36)), 8),  # 5-point star, radii 1 and 0.4
        ([(0, 0), (4, 0), (4, 3), (3, 3), (3, 1), (1, 1), (1, 3), (0, 3)], 4 * 3 - 2 * 2, 6),  # a U (concave)
        ([(0, 0), (2, 1), (4, 0), (2, 4)], 8.0 - 2.0, 2),  # an arrow head: triangle 8 minus notch 2
    ],
)
def test_triangulation_area_and_count_are_the_hand_computed_ones(points, area, triangles):
    got_area, count, tris = area_and_count(points)
    assert count == triangles == len(points) - 2
    assert got_area == pytest.approx(area, rel=1e-12)
    assert shoelace(points) == pytest.approx(area, rel=1e-12)  # the figures are right
    # no triangle is flipped: all face the polygon's normal (+z here) in both windings
    pts, _ = polygon(points)
    n = np.cross(pts[tris[:, 1]] - pts[tris[:, 0]], pts[tris[:, 2]] - pts[tris[:, 0]])
    assert (n[:, 2] > -1e-12).all()
    back, count2, _ = area_and_count(points[::-1])
    assert (back, count2) == (pytest.approx(area, rel=1e-12), triangles)


def test_triangulation_in_3d_uses_the_polygons_own_plane():
    u_shape = np.array([(0, 0), (4, 0), (4, 3), (3, 3), (3, 1), (1, 1), (1, 3), (0, 3)], float)
    angle = 0.7
    rot = np.array([[1, 0, 0], [0, math.cos(angle), -math.sin(angle)], [0, math.sin(angle), math.cos(angle)]])
    pts = np.column_stack([u_shape, np.zeros(8)]) @ rot.T @ np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]])
    tris, _ = triangulate(pts + [5, -2, 1], [0, 8])
    assert triangle_areas(pts, tris).sum() == pytest.approx(8.0, rel=1e-12)


def test_many_polygons_at_once_keep_their_owner_and_skip_those_without_area():
    square = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
    line = [(0, 0, 0), (1, 1, 1), (2, 2, 2)]
    ell = [(0, 0, 5), (2, 0, 5), (2, 1, 5), (1, 1, 5), (1, 2, 5), (0, 2, 5)]
    pts = np.array(square + line + ell, float)
    tris, owner = triangulate(pts, [0, 4, 7, 13])
    assert owner.tolist() == [0, 0, 2, 2, 2, 2]
    assert np.bincount(owner, triangle_areas(pts, tris), minlength=3) == pytest.approx([1.0, 0.0, 3.0])


def test_a_turtle_square_closes_on_its_first_vertex():
    sk = LSystem.from_text("n: 0\nw: {f+f+f+f}").derive().skeleton()
    assert len(sk) == 0  # f inside a polygon draws no branch
    assert sk.polygons.sizes.tolist() == [4]
    assert sk.polygons.areas() == pytest.approx([1.0])


def test_F_inside_a_polygon_records_a_vertex_and_draws_no_branch():
    sk = LSystem.from_text("n: 0\nw: F{F+F+F+F+}F").derive().skeleton()
    assert len(sk) == 2
    assert sk.polygons.sizes.tolist() == [4]
    np.testing.assert_allclose(sk.end[1], [0, 0, 2], atol=1e-12)  # the turtle came back to where { started


def test_G_moves_inside_a_polygon_without_a_vertex_and_dot_records():
    sk = LSystem.from_text("n: 0\nw: {.G.+G.+G.+G}").derive().skeleton()
    # {. at the origin, then three corners recorded by '.'; the last G returns without a vertex
    assert sk.polygons.sizes.tolist() == [4]
    assert sk.polygons.areas() == pytest.approx([1.0])
    assert len(LSystem.from_text("n: 0\nw: G(5)F").derive().skeleton()) == 1  # G outside: nothing


def test_nested_polygons_get_their_own_vertices():
    sk = LSystem.from_text("n: 0\nw: {f+f[{f+f+f+}]+f+}").derive().skeleton()
    assert sk.polygons.sizes.tolist() == [4, 4]
    assert sk.polygons.areas() == pytest.approx([1.0, 1.0])


def test_a_polygon_may_close_after_the_branch_that_opened_it():
    # ABOP fig. 5.5 style: '{' inside a branch, '}' after its ']' (polygons have their own stack)
    sk = LSystem.from_text("#angle 90\nn: 0\nw: [+f{.]f.+f.}").derive().skeleton()
    np.testing.assert_allclose(sk.polygons.points, [[-1, 0, 0], [0, 0, 1], [-1, 0, 1]], atol=1e-12)


def fig_1_26():
    return LSystem.from_text(FIG_1_26)


def rewrite_tokens(ls, words, steps):
    """An independent rewriter of the book's productions (token lists, no parameters)."""
    rules = {r.pred.symbol: [m.symbol for m in r.successor] for r in ls.grammar.rules}
    for _ in range(steps):
        words = [w for word in words for w in rules.get(word, [word])]
    return "".join(words)


def test_fig_1_26_derives_to_the_books_strings():
    ls = fig_1_26()
    assert ls.derive(n=1).to_string() == "internode+[plant+flower]--//[--leaf]internode[++leaf]-[plantflower]++plantflower"
    assert ls.derive(n=2).to_string().startswith("Fseg[//&&leaf][//^^leaf]Fseg+[internode+[plant+flower]")
    for n in range(6):
        assert ls.derive(n=n).to_string() == rewrite_tokens(ls, ["plant"], n)


def test_fig_1_26_leaves_and_wedges_have_the_hand_computed_areas():
    d = fig_1_26().derive()
    sk = d.skeleton()
    kinds = d.to_string().count("{")
    assert len(sk.polygons) == kinds > 100
    sizes, areas = sk.polygons.sizes, sk.polygons.areas()
    leaf, wedge = sizes == 8, sizes == 4
    assert (leaf | wedge).all() and leaf.any() and wedge.any()
    # leaf {+f-ff-f+|+f-ff-f}: two caps (2 s c) and a 2s x 2 band; wedge: a parallelogram of area s
    np.testing.assert_allclose(areas[leaf], 2 * S18 * C18 + 4 * S18, rtol=1e-9)
    np.testing.assert_allclose(areas[wedge], S18, rtol=1e-9)
    # colour: leaves after ['; wedges after pedicel' (the wedge's own ' is in its [ ] with the F)
    assert set(sk.polygons.color[leaf].tolist()) == {1}
    assert set(sk.polygons.color[wedge].tolist()) == {1}
    assert set(sk.color.tolist()) == {0, 2}  # pedicel's F before its quote, the wedge's F after one more
    # each polygon's leaf id is its '{' module in the current string
    symbols = np.array(d.lsystem.symbols)[d.tree.symbol[sk.polygons.leaf_id]]
    assert set(symbols.tolist()) == {"{"}
    assert np.isin(sk.polygons.leaf_id, d.tree.leaves).all()


def test_the_mesh_maps_polygon_triangles_to_their_leaf_ids_and_materials():
    sk = fig_1_26().derive(n=3).skeleton()
    mesh = sk.to_polydata(sides=4)
    poly = np.asarray(mesh.cell_data["polygon"])
    cells = np.flatnonzero(poly >= 0)
    tris, owner = sk.polygons.triangles()
    assert len(cells) == len(tris) and (cells == np.arange(mesh.n_cells - len(tris), mesh.n_cells)).all()
    np.testing.assert_array_equal(mesh.cell_data["leaf_id"][cells], sk.polygons.leaf_id[owner])
    np.testing.assert_array_equal(mesh.cell_data["material"][cells], sk.polygons.color[owner])
    assert (mesh.cell_data["kind"][cells] == 1).all()
    assert (mesh.cell_data["segment"][cells] == -1).all() and (mesh.cell_data["organ"][cells] == -1).all()
    # the area of the mesh's polygon cells is the polygons' area
    surf = mesh.extract_cells(cells).compute_cell_sizes()
    assert surf.cell_data["Area"].sum() == pytest.approx(sk.polygons.areas().sum(), rel=1e-9)


def test_polygons_select_by_leaf_id():
    sk = fig_1_26().derive(n=3).skeleton()
    first = int(sk.polygons.leaf_id[0])
    assert sk.polygons.select([first]).tolist() == [True] + [False] * (len(sk.polygons) - 1)
    assert isinstance(Polygons.empty(), Polygons) and len(Polygons.empty()) == 0


# -- bad input ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    "axiom, column, fragment",
    [
        ("F}F", 5, "no polygon is open"),
        ("F{f+f+fF", 5, "never closed"),
        ("F.F", 5, "outside any polygon"),
        ("{.f.}", 4, "fewer than 3 vertices"),  # at most 2 distinct points: { and one move
    ],
)
def test_polygon_mistakes_in_the_axiom_are_grammar_errors_with_a_caret(axiom, column, fragment):
    with pytest.raises(GrammarError) as info:
        LSystem.from_text(f"n: 1\nw: {axiom}\np:\n A -> B")
    err = info.value
    assert fragment in err.message and (err.line, err.column) == (2, column)
    assert str(err).splitlines()[-1] == " " * (column + 1) + "^"


def test_a_short_polygon_written_in_a_rule_is_a_grammar_error():
    with pytest.raises(GrammarError, match="fewer than 3 vertices") as info:
        LSystem.from_text("n: 1\nw: A\np:\n A -> F[{.f.}]")
    assert (info.value.line, info.value.column) == (4, 9)


def test_mistakes_only_the_derivation_shows_name_the_rule_that_wrote_the_module():
    ls = LSystem.from_text("n: 2\nw: A\np:\n A -> B{f+f+f\n B -> F.")
    with pytest.raises(DerivationError) as info:
        ls.derive().skeleton()
    err = info.value
    assert "outside any polygon" in err.message and "rule 2" in err.message
    assert (err.line, err.column) == (5, 8)
    ls = LSystem.from_text("n: 1\nw: A\np:\n A -> F{f+f+fB\n B -> }")
    with pytest.raises(DerivationError, match="never closed") as info:
        ls.derive().skeleton()
    assert (info.value.line, info.value.column) == (4, 8)


def test_abop_rose_leaf_successors_close_before_they_open():
    # ABOP fig. 5.7's rule shape: '}' before '{' in one successor is fine
    text = """n: 4
w: [{A(0).}]
p:
  A(t) -> .G(1).[+B(t)G(0.5).}][+B(t){.]A(t+1)
  B(t) : t > 0 -> G(1)B(t-1)
"""
    sk = LSystem.from_text(text).derive().skeleton()
    areas = sk.polygons.areas()
    assert len(sk.polygons) == 5 and (areas[:-1] > 0).all()  # the newest one has not grown yet
    assert areas[-1] == 0 and sk.polygons.sizes[-1] == 1


# -- pick, select, regrow ------------------------------------------------------------------
STOCHASTIC_LEAVES = """#module plant leaf
#angle 30
n: 4
w: plant
p:
  plant -> F[+leaf]F[-leaf]plant
  .5 leaf -> ['{+f-ff-f+|+f-ff-f}]
  .5 leaf -> [''{+f(2)-f|+f-f(2)}]
"""


def test_a_picked_polygon_leaf_is_selected_and_regrown_with_fresh_leaf_ids():
    from ramure.app.model import Explorer, mesh_sides

    ex = Explorer(STOCHASTIC_LEAVES, seed=1)
    mesh = ex.mesh
    poly_cells = np.flatnonzero(np.asarray(mesh.cell_data["polygon"]) >= 0)
    cell = int(poly_cells[len(poly_cells) // 2])
    leaf = ex.leaf_of_cell(cell)
    tree = ex.derivation.tree
    assert ex.lsystem.symbols[tree.symbol[leaf]] == "{"
    old = ex.skeleton.polygons
    old_size = tree.size
    ex.select([leaf])
    result = ex.regrow(seed=5)
    assert result.added > 0
    new = ex.skeleton.polygons
    d = ex.derivation
    # every polygon is drawn by a '{' of the current string; the regrown ones by new nodes
    assert np.isin(new.leaf_id, d.tree.leaves).all()
    assert set(np.array(ex.lsystem.symbols)[d.tree.symbol[new.leaf_id]].tolist()) == {"{"}
    fresh = new.leaf_id >= old_size
    assert fresh.any() and leaf not in new.leaf_id.tolist()
    kept = np.isin(old.leaf_id, new.leaf_id)
    assert kept.sum() == (~fresh).sum() == len(old) - (~kept).sum()
    # the kept polygons are where they were
    o = {int(i): old.points[old.offsets[k] : old.offsets[k + 1]] for k, i in enumerate(old.leaf_id)}
    for k in np.flatnonzero(~fresh):
        np.testing.assert_array_equal(new.points[new.offsets[k] : new.offsets[k + 1]], o[int(new.leaf_id[k])])
    # the mesh after the edit maps its polygon cells to the new ids, and equals a full rebuild
    mesh = ex.mesh
    cells = np.flatnonzero(np.asarray(mesh.cell_data["polygon"]) >= 0)
    assert set(np.asarray(mesh.cell_data["leaf_id"])[cells].tolist()) == set(new.leaf_id.tolist())
    full = d.skeleton().to_polydata(sides=mesh_sides(len(ex.skeleton)))
    assert mesh.points.dtype == np.float32  # the explorer's mesh: float64 points rounded once
    np.testing.assert_array_equal(np.asarray(mesh.points), np.asarray(full.points).astype(np.float32))
    np.testing.assert_array_equal(np.asarray(mesh.cell_data["leaf_id"]), np.asarray(full.cell_data["leaf_id"]))
    ex.undo()
    np.testing.assert_array_equal(ex.skeleton.polygons.leaf_id, old.leaf_id)
    np.testing.assert_array_equal(ex.skeleton.polygons.points, old.points)


def test_an_edit_near_a_polygon_that_crosses_a_branch_redraws_the_whole_plant():
    from ramure.lsys.interpretation.turtle import changed_spans, interpret_string, reinterpret

    # ABOP fig. 5.5-style: each '{' opens in a branch and closes after its ']'
    s = Session(LSystem.from_text("n: 5\nw: [A][B]\np:\n A -> [+A{.].C.}\n B -> [-B{.].C.}\n C -> GC"), seed=1)
    old = s.derivation.skeleton()
    before = s.tree.leaves
    s.regrow(s.leaves_with_symbol("C")[:2], seed=4)
    spans = changed_spans(before, s.tree.leaves, s.tree.size)
    new = reinterpret(s.lsystem, s.tree, old, s.tree.leaves, *spans)
    full = interpret_string(s.lsystem, s.tree, s.tree.leaves)
    assert "reuse" not in new.extra and len(full.polygons) == 10
    np.testing.assert_array_equal(new.polygons.points, full.polygons.points)


def test_skeleton_bounds_hold_the_polygons():
    sk = LSystem.from_text("n: 0\nw: F{+(90)f(5)-(90)f-(90)f(5)}").derive().skeleton()
    low, high = sk.bounds()
    assert low[0] == pytest.approx(-5.05) and high[2] == pytest.approx(2.05)  # width 0.1 pads by 0.05


def test_a_polygon_error_in_new_text_or_count_keeps_the_explorers_plant():
    from ramure.app.model import Explorer

    ex = Explorer("n: 2\nw: A\np:\n A -> {f+fB\n B -> f+f}C\n C -> D")
    before = (ex.text, len(ex.skeleton.polygons), ex.mesh.n_cells)
    err = ex.set_text("n: 2\nw: A\np:\n A -> B{f+f+f\n B -> F.")
    assert isinstance(err, DerivationError) and (err.line, err.column) == (5, 8)
    assert (ex.text, len(ex.skeleton.polygons), ex.mesh.n_cells) == before
    with pytest.raises(DerivationError, match="never closed"):
        ex.set_derivation(n=1)  # at n = 1 the '}' is not written yet
    assert ex.session.n == 2 and (ex.text, len(ex.skeleton.polygons), ex.mesh.n_cells) == before
    assert ex.set_text("n: 1\nw: {f+f+f}") is None and len(ex.skeleton.polygons) == 1


def test_an_explorer_on_a_grammar_whose_polygon_never_closes_is_refused_at_once():
    from ramure.app.model import Explorer

    with pytest.raises(DerivationError, match="never closed"):
        Explorer("n: 1\nw: A\np:\n A -> {f+fB\n B -> f+f}C")  # at n = 1 the '}' is not written yet


def test_a_polygon_that_overflows_names_its_module():
    with pytest.raises(DerivationError, match=r"not finite at module \{"):
        LSystem.from_text("n: 0\nw: F{f(1e308)f(1e308)+f}").derive().skeleton()


def test_a_polygon_material_out_of_range_is_refused():
    with pytest.raises(DerivationError, match="colour index"):
        LSystem.from_text("n: 0\nw: F;(1e12){f+f+f}").derive().skeleton()


def test_a_huge_concave_outline_is_triangulated_at_once():
    import time

    k = 100_000  # a comb: a concave outline far beyond what ear clipping does quickly
    x = np.repeat(np.arange(k // 2, dtype=float), 2)
    y = np.tile([0.0, 1.0], k // 2)
    y[1::4] = 0.5
    pts = np.column_stack([np.r_[x, x[-1], 0.0], np.r_[y, -1.0, -1.0], np.zeros(k + 2)])
    triangulate(pts[:4], [0, 4])  # compiled (or loaded from numba's cache) before timing
    t0 = time.process_time()
    tris, _ = triangulate(pts, [0, len(pts)])
    assert len(tris) == len(pts) - 2 and time.process_time() - t0 < 2.0
