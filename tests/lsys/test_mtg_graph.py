"""Reading MTG files as OpenAlea writes them (small files written here, one construct each)."""

import json
import re
import subprocess
import sys

import numpy as np
import pytest

from ramure.lsys.architecture.mtg import MTGError
from ramure.lsys.architecture.mtg_graph import parse_mtg_graph, read_mtg_graph

CLASSES = """CODE:\tFORM-A
CLASSES:
SYMBOL\tSCALE\tDECOMPOSITION\tINDEXATION\tDEFINITION
$\t0\tFREE\tFREE\tIMPLICIT
P\t1\tFREE\tFREE\tIMPLICIT
U\t2\tFREE\tFREE\tIMPLICIT
E\t3\tFREE\tFREE\tIMPLICIT
DESCRIPTION :
LEFT\tRIGHT\tRELTYPE\tMAX
U\tU,E\t<\t1
U\tU\t+\t?
"""
FEATURES = """FEATURES:
NAME\tTYPE
len\tREAL
n\tINT
note\tALPHA
when\tDD/MM/YY
"""
# Two plants; a branch in column 2; `<<E3` repeats '<'; features in any column.
TWO_PLANTS = (
    CLASSES
    + FEATURES
    + "MTG:\nTOPO\t\t\tlen\tn\tnote\twhen\n"
    + "/P1/U1/E1\t\t\t2.5\t3\told\t01/05/99\n"
    + "^<E2\t\t\t1.5\n"
    + "\t+U2/E1\t\t0.5\t\tbud\n"
    + "^<U3/E1<<E3\t\t\t\t\t\t12/06/00\n"
    + "/P2/U1/E1\n"
)
# The shape of openalea/mtg's mtg1.mtg (written here): one class at scale 1, five '^<'.
CHAIN = """CODE:\tFORM-A
CLASSES:
SYMBOL\tSCALE\tDECOMPOSITION\tINDEXATION\tDEFINITION
$ \t0\tFREE\tFREE\tIMPLICIT
A \t1\tFREE\tFREE\tEXPLICIT
DESCRIPTION :
LEFT\tRIGHT\tRELTYPE\tMAX
A\tA\t<\t1
FEATURES:
NAME\tTYPE\t
nbEl\tINT
MTG:
ENTITY-CODE\t\t\t\t\tnbEl

/A1
^<A1
^<A1\t
^<A1
^<A1
^<A1
"""


def test_a_chain_of_six_is_one_chain_not_six_axes():
    g = parse_mtg_graph(CHAIN)
    assert g.vertices_per_scale() == {1: 6}
    assert g.parent[1:].tolist() == [-1, 1, 2, 3, 4, 5]
    assert g.edge[1:].tolist() == ["", "<", "<", "<", "<", "<"]
    assert g.plants() == 1 and g.classes == {"A": 1}


def test_scales_edges_and_complexes_as_openalea_builds_them():
    g = parse_mtg_graph(TWO_PLANTS)
    assert g.label == ["$", "P1", "U1", "E1", "E2", "U2", "E1", "U3", "E1", "E2", "E3", "P2", "U1", "E1"]
    assert g.scale.tolist() == [0, 1, 2, 3, 3, 2, 3, 2, 3, 3, 3, 1, 2, 3]
    assert g.complex.tolist() == [-1, 0, 1, 2, 2, 1, 5, 1, 7, 7, 7, 0, 11, 12]
    assert g.parent.tolist() == [-1, -1, -1, -1, 3, 2, 4, 2, 4, 8, 9, -1, -1, -1]
    # U2 branches from U1 because its first element branches from U1's E2 (OpenAlea's fat_mtg)
    assert g.edge.tolist() == ["", "", "", "", "<", "+", "+", "<", "<", "<", "<", "", "", ""]
    assert g.plants() == 2
    assert g.edges_by_type() == {"<": 5, "+": 2, "/": 11}


def test_features_are_typed_and_land_on_the_last_entity_of_their_line():
    g = parse_mtg_graph(TWO_PLANTS)
    assert g.features["len"][3:7] == [2.5, 1.5, None, 0.5]
    assert g.features["n"][3] == 3 and isinstance(g.features["n"][3], int)
    assert g.features["note"][6] == "bud" and g.features["when"][10] == "12/06/00"
    assert g.feature_types == {"len": "REAL", "n": "INT", "note": "ALPHA", "when": "DD/MM/YY"}


def test_a_latin1_file_is_detected(tmp_path):
    path = tmp_path / "hetre.mtg"
    path.write_bytes(TWO_PLANTS.replace("bud", "hêtre").encode("latin-1"))
    g = read_mtg_graph(path)
    assert g.encoding == "latin-1" and g.features["note"][6] == "hêtre"
    path.write_bytes(TWO_PLANTS.replace("bud", "hêtre").encode("utf-8"))
    assert read_mtg_graph(path).encoding == "utf-8" and read_mtg_graph(path).features["note"][6] == "hêtre"


def test_dated_lines_add_values_to_the_entity_above():
    text = TWO_PLANTS.replace("^<E2\t\t\t1.5\n", "^<E2\t\t\t1.5\n*\t\t\t1.75\t\t\t03/07/99\n")
    g = parse_mtg_graph(text)
    assert g.dated == {4: [{"len": 1.75, "when": "03/07/99"}]} and g.features["len"][4] == 1.5
    assert len(g) == 14


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("^<U3/E1<<E3", "^<U3/X1", "line 23: class 'X' of 'X1' is not declared in CLASSES"),
        ("/P2/U1/E1", "/P2/E1", "line 24: '/E1' lands at scale 2, but class 'E' is at scale 3"),
        ("\t+U2/E1\t\t0.5", "\t\t\t+U2/E1\t0.5", "line 22: the entity code stands in a feature column"),
        ("\t\t\t2.5\t3", "\t\t\t2.5\t3.5", "line 20: feature n = '3.5' is not of type INT"),
        ("TOPO\t\t\tlen", "TOPO\t\t\tlength", "line 19: feature 'length' is not declared in FEATURES"),
        ("when\tDD/MM/YY", "when\tCOLOUR", "line 17: feature 'when' has type 'COLOUR'"),
        ("^<E2\t", "\t^<E2\t", "line 21: '^' on a line indented deeper than the line before"),
    ],
)
def test_a_misread_is_an_error_naming_the_line(old, new, message):
    assert old in TWO_PLANTS
    with pytest.raises(MTGError, match=re.escape(message)):
        parse_mtg_graph(TWO_PLANTS.replace(old, new, 1))


def test_a_column_that_matches_no_line_above_is_refused():
    text = TWO_PLANTS.replace("/P2/U1/E1\n", "\t\t+U9/E1\n\t^<E2\n")
    with pytest.raises(MTGError, match="line 25: column 2 matches no line above"):
        parse_mtg_graph(text)


def test_command_line_prints_counts_per_scale(tmp_path):
    (tmp_path / "two.mtg").write_text(TWO_PLANTS)
    out = subprocess.run(
        [sys.executable, "-m", "ramure.app.cli", "mtg", str(tmp_path / "two.mtg")], capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr
    facts = json.loads(out.stdout)
    assert facts["vertices_per_scale"] == {"1": 2, "2": 4, "3": 7}
    assert facts["classes"] == {"P": 1, "U": 2, "E": 3} and facts["features"]["len"] == "REAL"
    assert facts["edges"] == {"<": 5, "+": 2, "/": 11} and facts["plants"] == 2
    (tmp_path / "bad.mtg").write_text(TWO_PLANTS.replace("/P2/U1/E1", "/P2/E1"))
    bad = subprocess.run(
        [sys.executable, "-m", "ramure.app.cli", "mtg", str(tmp_path / "bad.mtg")], capture_output=True, text=True
    )
    assert bad.returncode == 2 and "line 24" in bad.stderr and "Traceback" not in bad.stderr


def test_the_per_scale_counts_are_arrays():
    g = parse_mtg_graph(TWO_PLANTS)
    assert np.array_equal(g.at_scale(1), [1, 11])


def test_mutated_files_raise_only_mtg_errors():
    import random

    from ramure.lsys import LSystem
    from ramure.lsys.architecture.mtg_plant import mtg_grammar_text

    rnd = random.Random(7)
    read = 0
    for _ in range(400):
        chars = list(TWO_PLANTS)
        for _ in range(rnd.randint(1, 3)):
            k = rnd.randrange(len(chars))
            chars[k : k + rnd.randint(0, 1)] = rnd.choice(["", "\t", "\n", "/", "<", "+", "^", "*", "[", "E", "9", "<<E"])
        try:
            graph = parse_mtg_graph("".join(chars))
        except MTGError:
            continue
        read += 1
        LSystem.from_text(mtg_grammar_text(graph)).derive().skeleton()  # what reads, draws
    assert 0 < read < 400
