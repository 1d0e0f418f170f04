"""cpfg's ``func(id, x)`` (issue 36): B-spline functions from the ``.func`` files the view file
names.  The function used here has control points (0,0) (1/3,0) (2/3,1) (1,1): four points, so
the curve is a cubic Bezier with x(s) = s and y(s) = 3s^2 - 2s^3 (worked out by hand)."""

import pytest

from ramure.lsys import GrammarError, LSystem

SMOOTH = "fver 1 1\nname: smooth\nsamples: {samples}\nflip: off\npoints: 4\n0 0 1\n0.333333 0 1\n0.666667 1 1\n1 1 1\n"
STEP = "fver 1 1\nname: FADE\nsamples: 3\nflip: off\npoints: 4\n0 1\n0.333333 1\n0.666667 1\n1 1\n"


def folder(tmp_path, rules, view="function: smooth.func\n", samples=5):
    (tmp_path / "smooth.func").write_text(SMOOTH.format(samples=samples))
    (tmp_path / "plant.v").write_text("angle factor: 8\n" + view)
    path = tmp_path / "plant.l"
    path.write_text(f"Lsystem: 1\nderivation length: 1\n{rules}\nendlsystem\n")
    return path


def values(path):
    return [args[0] for _, args in LSystem.from_file(path).derive().modules]


def test_func_reads_the_curve_at_x_sampled_as_cpfg_samples_it(tmp_path):
    path = folder(tmp_path, "axiom: A(0.25)A(0.5)A(0.125)A(2)\nA(x) --> B(func(1, x))")
    got = values(path)
    assert got[:2] == pytest.approx([0.15625, 0.5], abs=0.002)  # y(0.25), y(0.5): on the samples
    assert got[2] == pytest.approx(0.15625 / 2, abs=0.002)  # between samples 0 and 0.25: linear
    assert got[3] == pytest.approx(1.0, abs=0.002)  # x > 1 reads the value at 1


def test_a_function_without_samples_is_computed_exactly(tmp_path):
    path = folder(tmp_path, "axiom: A(0.125)\nA(x) --> B(func(1, x))", samples=0)
    assert values(path) == pytest.approx([3 / 64 - 2 / 512], abs=0.002)


def test_a_function_set_names_its_functions_and_blocks_call_func(tmp_path):
    (tmp_path / "f.fset").write_text("funcgalleryver 1 1\nitems: 2\n" + SMOOTH.format(samples=5) + STEP)
    rules = "Start: {k = func(FADE, 0.3) + func(1, 0.5);}\naxiom: A\nA --> B(k, FADE)"
    path = folder(tmp_path, rules, view="function: smooth.func 10\nfunction set: f.fset\n")
    assert LSystem.from_file(path).derive().modules == [("B", pytest.approx((1.5, 2.0), abs=0.002))]


def test_an_unknown_id_is_named_with_the_rule(tmp_path):
    path = folder(tmp_path, "axiom: A(3)\nA(x) --> B(func(x, 0.5))")
    with pytest.raises(Exception, match=r"func\(3, x\): the view file names 1 function"):
        LSystem.from_file(path).derive()


def test_without_a_view_file_func_is_refused_with_the_reason(tmp_path):
    path = tmp_path / "plant.l"
    path.write_text("derivation length: 1\naxiom: A\nA --> B(func(1, 0.5))\n")
    with pytest.raises(GrammarError, match="no view file beside the .l file") as info:
        LSystem.from_file(path)
    assert (info.value.line, info.value.column) == (3, 9)  # at func


def test_files_outside_the_grammars_folder_are_refused_at_the_view_files_line(tmp_path):
    inner = tmp_path / "model"
    inner.mkdir()
    (tmp_path / "secret.func").write_text(SMOOTH.format(samples=5))
    path = folder(inner, "axiom: A\nA --> B(func(1, 0.5))", view="\nfunction: ../secret.func\n")
    with pytest.raises(GrammarError, match="outside the grammar's folder") as info:
        LSystem.from_file(path)
    assert info.value.line == 3 and info.value.filename == str(inner / "plant.v")


def test_import_to_lsys_refuses_func_at_its_call(tmp_path):
    from ramure.lsys.language.cpfg import to_lsys

    path = folder(tmp_path, "axiom: A\nA --> B(func(1, 0.5))")
    with pytest.raises(GrammarError, match="open the .l file itself") as info:
        to_lsys(path.read_text(), str(path))
    assert (info.value.line, info.value.column) == (4, 9)
