"""Bounds before work (issue 37, item 6): a value that cannot give a result is refused before
anything is built, with a message naming the value, and never runs out of time or memory."""

from __future__ import annotations

import contextlib
import io
import pathlib

import pytest

from ramure.app.cli import main
from ramure.errors import RamureError, ValueRefused
from ramure.gmap.organs import wood as W


def run_cli(argv):
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            rc = main(argv)
        except SystemExit as exc:
            rc = exc.code
    return rc, err.getvalue()


@pytest.fixture
def no_wood_built(monkeypatch):
    """Fail the test if a Wood is ever constructed: the refusal must come first."""

    def built(*_args, **_kwargs):
        raise AssertionError("a Wood was built before the values were checked")

    monkeypatch.setattr(W, "Wood", built)


@pytest.mark.parametrize(
    "setting, words",
    [
        ({"branches": "1e308"}, "branches do not fit: 9 years of 16 trunk faces hold at most 144"),
        ({"branches": "1e7"}, "10,000,000 branches do not fit"),
        ({"branches": "inf"}, "branches must be a finite number"),
        ({"height": "1e308"}, "height must be at most 1000 m"),
        ({"height": "nan"}, "height must be a finite number"),
        ({"pith_radius": "5e3"}, "pith_radius must be at most 1000 m"),
        ({"sides": "1e9"}, "sides must be at most 1024"),
        ({"branches": "2.5"}, "branches must be a whole number"),
    ],
)
def test_wood_values_are_refused_before_growing(no_wood_built, setting, words):
    with pytest.raises(ValueRefused, match=words):
        W.grow_wood("pine", years=10, **setting)


def test_the_largest_branch_count_that_fits_is_still_placed():
    p = W.resolve_params("pine")
    placed = W.place_branches(p, years=10, seed=0, count=144)
    assert len(placed) == 144
    with pytest.raises(ValueRefused, match="145 branches do not fit"):
        W.place_branches(p, years=10, seed=0, count=145)


@pytest.mark.parametrize(
    "setting, words",
    [("branches=1e308", "branches do not fit"), ("branches=inf", "finite"), ("height=1e308", "at most 1000 m")],
)
def test_ramure_wood_refuses_with_exit_2(tmp_path, setting, words):
    out = tmp_path / "w.png"
    rc, err = run_cli(["wood", "--set", setting, "-o", str(out)])
    assert rc == 2 and words in err and "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize(
    "select, words",
    [
        ("0-9999999", "the range '0-9999999' names more than 100,000 ids"),  # refused from the text alone
        ("99999", "99999 is not a leaf of the current plant"),
        ("50000-60000", "the range 50000-60000 holds no leaf"),  # measured against the plant
    ],
)
def test_ramure_regen_reads_select_against_the_plant(select, words):
    rc, err = run_cli(["regen", "honda_sympodial", "-n", "5", "--select", select])
    assert rc == 2 and f"--select: {words}" in err


def test_ramure_regen_range_means_the_leaves_inside_it(capsys):
    import json

    from ramure.lsys import LSystem

    tree = LSystem.from_file("honda_sympodial").derive(n=5).tree
    leaves = sorted(int(i) for i in tree.leaves)
    a, b = leaves[-6], leaves[-1]
    assert main(["regen", "honda_sympodial", "-n", "5", "--select", f"{a}-{b}", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert set(record["selection"]) == {i for i in leaves if a <= i <= b}


def test_a_picture_that_cannot_fit_in_memory_is_refused_before_rendering(tmp_path, monkeypatch):
    from ramure.app.commands import plant

    monkeypatch.setattr(plant, "available_memory", lambda: 4 * 2**30)  # a 4 GB machine
    out = tmp_path / "p.png"
    rc, err = run_cli(["render", "honda_sympodial", "-n", "2", "--size", "10000x10000", "-o", str(out)])
    assert rc == 2 and "needs about 6.3 GB to render, and 4.0 GB of memory is available" in err
    assert not out.exists()
    assert plant.parse_size("4000x4000") == (4000, 4000)  # 1.0 GB fits


TERNARY = pathlib.Path(__file__).resolve().parents[2] / "grammars" / "ternary_branching.lsys"


def _saved_session(tmp_path, edits):
    """A session file of the ternary plant with ``edits`` real regrows."""
    from ramure.lsys import LSystem
    from ramure.lsys.regeneration.regen import Session

    session = Session(LSystem.from_file("ternary_branching"), n=3, seed=1)
    for _ in range(edits):
        session.regrow([int(session.tree.leaves[-1])], rho=0.5)
    return session.save(tmp_path / "s.json")


def test_a_session_of_too_many_edits_is_refused_before_any_replay(tmp_path, monkeypatch):
    """Issue 37, item 6: 2,000 edits replayed for 4.3 s with no word; the count is checked first."""
    import json

    from ramure.app.model import Explorer
    from ramure.lsys.regeneration import regen

    path = _saved_session(tmp_path, 1)
    data = json.loads(path.read_text())
    data["edits"] = data["edits"] * 2000
    path.write_text(json.dumps(data))
    ex = Explorer(TERNARY, n=2)
    before = ex.session.derivation.to_string()
    monkeypatch.setattr(regen.Session, "_apply", lambda *_: pytest.fail("an edit was replayed before the count was checked"))
    with pytest.raises(RamureError, match="it holds 2,000 edits; a session replays at most 1,000"):
        ex.load_session(path)
    assert ex.session.derivation.to_string() == before
    assert regen.MAX_SESSION_EDITS == 1000


def test_a_session_replay_reports_its_progress(tmp_path):
    from ramure.app.model import Explorer

    path = _saved_session(tmp_path, 3)
    calls = []
    ex = Explorer(TERNARY, n=2)
    ex.load_session(path, progress=lambda done, total: calls.append((done, total)))
    assert calls == [(1, 3), (2, 3), (3, 3)]
    assert len(ex.session.edits) == 3
