"""Surfaces ~name, spheres @O, per-branch tropism @Ts, materials ;(i), the cut % (issue 15, part A)."""

import numpy as np
import pytest

from ramure.errors import GrammarError
from ramure.lsys import LSystem
from ramure.lsys.interpretation.polygons import triangle_areas
from ramure.lsys.regeneration.regen import Session
from ramure.lsys.interpretation.surfaces import LIBRARY, shipped


def skeleton(text):
    return LSystem.from_text(text).derive().skeleton()


# -- surfaces -----------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["leaf", "petal", "sepal"])
def test_a_shipped_surface_is_placed_scaled_along_the_heading(name):
    sk = skeleton(f"n: 0\nw: F(2)+(90)~{name}(3)")
    assert sk.organs.kind.tolist() == [f"~{name}"] and sk.organs.size.tolist() == [3.0]
    mesh = sk.to_polydata(sides=4)
    cells = np.flatnonzero(np.asarray(mesh.cell_data["organ"]) == 0)
    pts, tris = shipped(name)
    assert len(cells) == len(tris) > 20
    assert (mesh.cell_data["kind"][cells] == 1).all()  # drawn (and aged by seasons) as a leaf
    part = mesh.extract_cells(cells)
    xyz = np.asarray(part.points)
    # '+' turned the heading from +z to -x: the surface runs from (0,0,2) to its tip 3 units along -x
    assert xyz[:, 0].min() == pytest.approx(-3.0 * pts[:, 0].max()) and xyz[:, 0].max() == pytest.approx(0.0)
    area = triangle_areas(pts, tris).sum() * 9.0
    assert part.compute_cell_sizes().cell_data["Area"].sum() == pytest.approx(area, rel=1e-9)


def test_the_library_has_leaf_petal_and_sepal_with_tips_at_one():
    for name in ("leaf", "petal", "sepal"):
        pts, tris = LIBRARY[name]()
        assert pts[:, 0].min() == 0.0 and pts[:, 0].max() == pytest.approx(1.0)
        assert triangle_areas(pts, tris).min() > 0


def test_a_surface_defined_by_a_module_string():
    text = "#define k 2\n#surface square {f+f+f+f}\n#angle 90\nn: 0\nw: ~square(k)"
    sk = skeleton(text)
    pts, tris = sk.extra["surfaces"]["~square"]
    assert triangle_areas(pts, tris).sum() == pytest.approx(1.0)
    mesh = sk.to_polydata()
    assert mesh.compute_cell_sizes().cell_data["Area"].sum() == pytest.approx(4.0)  # scaled by k = 2


def test_a_surface_made_by_a_polygon_sub_grammar_file(tmp_path):
    (tmp_path / "blade.lsys").write_text("#angle 90\nn: 2\nw: {A}\np:\n A -> f+f+f+f\n")
    main = tmp_path / "plant.lsys"
    main.write_text('#surface blade "blade.lsys"\nn: 0\nw: F~blade(0.5)\n')
    sk = LSystem.from_file(str(main)).derive().skeleton()
    pts, tris = sk.extra["surfaces"]["~blade"]
    assert triangle_areas(pts, tris).sum() == pytest.approx(1.0)
    with pytest.raises(GrammarError, match="no grammar file") as info:
        LSystem.from_text('#surface blade "missing.lsys"\nn: 0\nw: F', filename=str(main))
    assert info.value.line == 1


@pytest.mark.parametrize(
    "text, line, column, fragment",
    [
        ("n: 0\nw: F~leef(2)", 2, 5, "unknown surface 'leef'"),
        ("n: 1\nw: A\np:\n A -> F~blade", 4, 8, "unknown surface 'blade'"),
        ("n: 0\nw: ~leaf(1,2)", 2, 4, "takes one parameter"),
        ("#surface tri {.f.}\nn: 0\nw: ~tri", 1, 14, "fewer than 3 vertices"),
        ("#surface tri {f+f+f+f}\nn: 0\nw: ~tri(k)", 3, 9, "unknown name"),
    ],
)
def test_surface_mistakes_are_grammar_errors_with_a_caret(text, line, column, fragment):
    with pytest.raises(GrammarError) as info:
        skeleton(text)
    err = info.value
    assert fragment in str(err) and (err.line, err.column) == (line, column)


# -- spheres, tropism, materials ---------------------------------------------------------
def test_a_sphere_has_the_radius_it_is_given():
    sk = skeleton("#width 0.4\nn: 0\nw: F(3)@O(0.5)F@O")
    assert sk.organs.kind.tolist() == ["@O", "@O"]
    assert sk.organs.size.tolist() == [1.0, 0.4]  # diameters: 2r, then the width
    mesh = sk.to_polydata(organ_resolution=16)
    cells = np.flatnonzero(np.asarray(mesh.cell_data["organ"]) == 0)
    xyz = np.asarray(mesh.extract_cells(cells).points)
    assert np.linalg.norm(xyz - [0, 0, 3], axis=1) == pytest.approx(np.full(len(xyz), 0.5))
    assert (mesh.cell_data["kind"][cells] == 3).all()


def test_per_branch_elasticity_bends_like_a_global_tropism():
    bent = skeleton("n: 0\nw: F@Ts(0.3)FFF")
    same = skeleton("#tropism 0 0 -1 0.3\nn: 0\nw: !F")  # not bent after its only F: compare by hand
    del same
    glob = skeleton("#tropism 1 0 0 0.3\nn: 0\nw: +(30)FFFF")
    local = skeleton("#tropism 1 0 0 0.0\nn: 0\nw: +(30)@Ts(0.3)FFFF")
    np.testing.assert_allclose(local.end, glob.end, atol=1e-12)
    # no #tropism: @Ts bends toward -z; the trunk is vertical so only a tilted branch bends
    assert np.allclose(bent.end[:, :2], 0)
    tilted = skeleton("n: 0\nw: +(45)[@Ts(0.2)FF]FF")
    assert tilted.end[1, 2] < tilted.end[3, 2] - 1e-3  # the branch droops; after ']' no more bending
    straight = skeleton("n: 0\nw: +(45)FF")
    np.testing.assert_allclose(tilted.end[2:], straight.end, atol=1e-12)
    off = skeleton("#tropism 1 0 0 0.3\nn: 0\nw: +(30)@Ts(0)FFFF")
    np.testing.assert_allclose(off.end, skeleton("n: 0\nw: +(30)FFFF").end, atol=1e-12)


def test_materials_select_by_index_and_ride_on_the_mesh():
    text = "#material 1 0.2 0.6 0.1\n#material 3 1 0.9 0.3 0.5\nn: 0\nw: F;(1)F'(3),F;(3){f+f+f+f}"
    ls = LSystem.from_text(text)
    assert ls.grammar.materials == {1: (0.2, 0.6, 0.1, 1.0), 3: (1.0, 0.9, 0.3, 0.5)}
    sk = ls.derive().skeleton()
    assert sk.color.tolist() == [0, 1, 2] and sk.polygons.color.tolist() == [3]  # ',' alone: minus 1 (cpfg, L-Py)
    mesh = sk.to_polydata(sides=4)
    mat = np.asarray(mesh.cell_data["material"])
    assert mat.tolist() == [0] * 4 + [1] * 4 + [2] * 4 + [3, 3]
    np.testing.assert_allclose(mesh.field_data["material_rgb"], [[1, 0.2, 0.6, 0.1], [3, 1, 0.9, 0.3]])
    np.testing.assert_allclose(mesh.field_data["material_rgba"][:, 4], [1.0, 0.5])


@pytest.mark.parametrize(
    "line, column, fragment",
    [
        ("#material 1 2 0 0", 13, "from 0 to 1"),
        ("#material 1 0.5", 11, "takes an index and a colour"),
        ("#material 1.5 0 0 0", 11, "whole number"),
    ],
)
def test_material_mistakes_are_grammar_errors(line, column, fragment):
    with pytest.raises(GrammarError) as info:
        LSystem.from_text(line + "\nn: 0\nw: F")
    assert fragment in info.value.message and (info.value.line, info.value.column) == (1, column)


# -- cut ----------------------------------------------------------------------------------
def test_cut_removes_the_rest_of_the_branch_each_step():
    ls = LSystem.from_text("n: 3\nw: A\np:\n A -> F[+A][-B]A\n B -> F%FF[+F]")
    d = ls.derive()
    assert "%" not in d.to_string() and "B" in d.to_string()
    assert ls.derive(n=2).to_string() == "F[+F[+A][-B]A][-F]F[+A][-B]A"
    # the history keeps the cut modules as nodes no longer in the string
    tree = d.tree
    cut_nodes = np.flatnonzero((tree.child_count[: tree.size] == 0) & ~np.isin(np.arange(tree.size), tree.leaves))
    assert len(cut_nodes) > 0
    assert set(np.array(ls.symbols)[tree.symbol[cut_nodes]].tolist()) == {"%", "F", "[", "+", "]"}


def test_cut_at_the_top_level_removes_the_rest_of_the_string_and_the_axiom_is_cut_too():
    assert LSystem.from_text("n: 0\nw: F[+F]%F[-F]").derive().to_string() == "F[+F]"
    assert LSystem.from_text("n: 1\nw: A\np:\n A -> F[-F%[+F]F]%FF").derive().to_string() == "F[-F]"


def test_regrow_after_a_cut_keeps_history_consistent():
    text = "n: 4\nw: A\np:\n A -> F[+A][-B]A\n .5 B -> F%F\n .5 B -> FF"
    s = Session(LSystem.from_text(text), seed=3)
    before = s.derivation.to_string()
    leaves = s.leaves_with_symbol("B")
    s.regrow(leaves[:3], seed=11)
    assert "%" not in s.derivation.to_string()
    s.undo()
    assert s.derivation.to_string() == before


def test_a_surface_file_that_draws_itself_is_a_cycle(tmp_path):
    (tmp_path / "loop.lsys").write_text('#surface me "loop.lsys"\nn: 0\nw: {f+f+f}~me\n')
    with pytest.raises(GrammarError, match="#surface cycle"):
        LSystem.from_file(str(tmp_path / "loop.lsys")).derive().skeleton()
