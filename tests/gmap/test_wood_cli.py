"""``ramure wood`` and ``ramure check FILE.g3l``: JSON facts, cuts, outputs, one-line refusals."""

import json

import numpy as np
import pytest
import pyvista as pv

from ramure.app.cli import main
from ramure.gmap.organs import wood as W


def run_json(capsys, *argv):
    assert main(["wood", *argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_json_facts_of_a_trunk(capsys):
    r = run_json(capsys, "--years", "3", "--set", "branches=0")
    assert r["darts"] == W.trunk_darts(16, 3) and r["volumes"] == W.trunk_volumes(16, 3)
    assert (r["chi"], r["boundary_chi"], r["valid"]) == (1, 2, True)
    assert r["tissues"]["pith"] == 3 and r["tissues"]["bark"] == 16 * 6
    assert r["seconds"] > 0 and r["darts_per_second"] > 0


def test_cut_reports_rings_and_knots(capsys, tmp_path):
    out = tmp_path / "slice.vtu"
    r = run_json(capsys, "--years", "5", "--cut", "z=0.2", "-o", str(out))
    assert r["rings"] == 5 and r["knots"] >= 0 and out.exists()
    higher = run_json(capsys, "--years", "5", "--set", "branches=0", "--cut", "z=1.25")
    assert higher["rings"] == 5 - 2  # level 2 of 5 (0.5 m a year): 3 years old
    grid = pv.read(str(out))
    assert grid.n_cells > 0 and grid.bounds[5] <= 0.2 + 1e-9
    assert not list(tmp_path.glob(".*"))  # the temporary file was renamed


def test_plank_png_is_not_blank(capsys, tmp_path):
    out = tmp_path / "plank.png"
    r = run_json(
        capsys,
        "--years",
        "6",
        "--set",
        "height=0.12",
        "--plank",
        "normal=x,offset=0.01,thickness=0.004",
        "-o",
        str(out),
        "--size",
        "300x300",
    )
    assert r["rings"] >= 2 and out.stat().st_size > 2000
    from PIL import Image

    pixels = np.asarray(Image.open(out).convert("RGB")).reshape(-1, 3)
    assert len(np.unique(pixels, axis=0)) > 8  # wood colours, not a blank picture


def rgb_of(colour):
    return [int(colour[i : i + 2], 16) for i in (1, 3, 5)]


PLANK = ["--years", "6", "--set", "height=0.12", "--plank", "normal=x,offset=0.01,thickness=0.004"]


def test_plank_png_is_a_readable_board_around_a_knot(capsys, tmp_path):
    # it drew the whole plank as a sliver 10 px wide, and wrote pale "sapwood" on grey
    from PIL import Image

    out = tmp_path / "plank.png"
    r = run_json(capsys, *PLANK, "-o", str(out), "--size", "600x600")
    pixels = np.asarray(Image.open(out).convert("RGB")).astype(int)
    board = (pixels < 250).any(axis=2)
    board[:40] = False  # the title
    board[int(600 * 0.55) :] = False  # the legend's band
    columns = np.flatnonzero(board.any(axis=0))
    assert columns.size > 0.9 * 600  # the length chosen fills the picture's width
    rows = np.flatnonzero(board[:, 90])
    assert rows.size > 0.18 * 600  # and the board is a board, not a line (0.2 before the bark was shed)
    early, late = (np.array(rgb_of(c)) for c in W.SPECIES["pine"]["colors"]["sapwood"])
    lines = 0
    for x in range(90, 520, 30):  # columns across the board, away from its ends
        column = pixels[np.flatnonzero(board[:, x]), x]
        is_late = np.abs(column - late).sum(axis=1) < np.abs(column - early).sum(axis=1)
        lines = max(lines, int(np.count_nonzero(np.diff(is_late.astype(int)) == 1)))
    assert lines >= 2 * (r["rings"] - 1)  # rings are lines: each latewood band crossed on both sides of the pith
    knot = np.all(pixels == rgb_of(W.SPECIES["pine"]["colors"]["knot"][1]), axis=2)
    assert knot.sum() > 100 and abs(np.flatnonzero(knot.any(axis=0)).mean() - 300) < 60  # centred on the knot
    assert r["plank_window"]["length"] > 0.1 and 0 < r["plank_window"]["at"] < 0.72
    legend = pixels[int(600 * 0.6) :, 300:]
    assert (np.abs(legend - [245, 245, 240]).max(axis=2) <= 2).sum() > 5000  # a light box
    assert (legend.max(axis=2) < 60).sum() > 500  # with dark text on it


def test_plank_that_misses_the_trunk_is_refused_without_a_picture(capsys, tmp_path):
    # it hit a branch only, wrote a PNG and reported "knots 1"
    out = tmp_path / "plank.png"
    argv = [a.replace("offset=0.01", "offset=0.05") for a in PLANK]
    assert main(["wood", *argv, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "misses the trunk" in err and "\n" not in err
    assert not list(tmp_path.iterdir())


def test_grammar_option_honours_the_files_steps(capsys, tmp_path):
    # the CLI grew every grammar 2 x 10 half-years, whatever its #steps said
    from ramure.gmap.lsystem.engine import G3LSystem

    text = open("grammars/wood/spiral.g3l").read().replace("#steps 6", "#steps 3")
    grammar = tmp_path / "spiral3.g3l"
    grammar.write_text(text)
    r = run_json(capsys, "--grammar", str(grammar))
    assert r["steps"] == 3 and r["years"] == 1.5
    assert r["darts"] == G3LSystem.from_file(str(grammar)).derive(3).gm.n_darts == 192 * 4 + 384 * 3
    r = run_json(capsys, "--grammar", str(grammar), "--years", "2")  # --years still wins
    assert r["steps"] == 4 and r["darts"] == 192 * 5 + 384 * 4


def test_grammar_option_runs_a_g3l(capsys):
    r = run_json(capsys, "--grammar", "grammars/wood/spiral.g3l", "--years", "2")
    assert r["darts"] == 192 * 5 + 384 * 4 and r["chi"] == 1 and "labels" in r


@pytest.mark.parametrize(
    "argv, words",
    [
        (["--years", "0"], "years"),
        (["--species", "baobab"], "unknown species"),
        (["--set", "early_min=nan"], "finite"),
        (["--set", "late_min=0.01", "--set", "late_max=0.001"], "must not exceed"),
        (["--set", "sides=2"], "at least 3"),
        (["--set", "flavour=1"], "unknown wood parameter"),
        (["--plank", "normal=0:0:0"], "non-zero"),
        (["--cut", "q=1"], "cut plane"),
        (["--years", "2", "--cut", "z=100"], "misses the wood"),
        (["--years", "2", "--plank", "normal=x,offset=0.3,thickness=0.02"], "misses the wood"),
        (["-o", "trunk.xyz"], ".vtu"),
    ],
)
def test_bad_input_exits_2_with_one_line(capsys, argv, words, tmp_path):
    argv = [a if a != "trunk.xyz" else str(tmp_path / "trunk.xyz") for a in argv]
    code = main(["wood", *argv])
    err = capsys.readouterr().err.strip()
    assert code == 2 and words in err and "\n" not in err and "Traceback" not in err
    assert not list(tmp_path.iterdir())


def test_check_reads_g3l(capsys, tmp_path):
    assert main(["check", "grammars/wood/trunk.g3l"]) == 0
    assert "10 rule(s)" in capsys.readouterr().out
    bad = tmp_path / "bad.g3l"
    bad.write_text("axiom: A(4)\n(p1) A -> A[B(4, q)]_E\n")
    assert main(["check", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "line 2, column 18" in err and "^" in err
