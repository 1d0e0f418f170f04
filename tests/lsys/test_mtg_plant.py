"""An MTG drawn as a plant: coordinates, diameters and the documented default geometry."""

import math

import numpy as np
import pytest

from ramure.lsys import LSystem
from ramure.lsys.architecture.mtg_graph import parse_mtg_graph
from ramure.lsys.architecture.mtg_plant import BRANCH_ANGLE, DIVERGENCE, PLANT_SPACING, mtg_grammar_text

HEAD = """CODE:\tFORM-A
CLASSES:
SYMBOL\tSCALE\tDECOMPOSITION\tINDEXATION\tDEFINITION
$\t0\tFREE\tFREE\tIMPLICIT
P\t1\tFREE\tFREE\tIMPLICIT
E\t2\tFREE\tFREE\tIMPLICIT
DESCRIPTION:
LEFT\tRIGHT\tRELTYPE\tMAX
FEATURES:
NAME\tTYPE
"""
# A trunk of two entities, a branch on the first: coordinates of each entity's top.
POINTS = (
    HEAD
    + "XX\tREAL\nYY\tREAL\nZZ\tREAL\nTopDia\tREAL\nMTG:\nENTITY-CODE\t\t\tXX\tYY\tZZ\tTopDia\n"
    + "/P1/E1\t\t\t0\t0\t3\t0.8\n"
    + "\t+E2\t\t4\t0\t6\t0.2\n"
    + "^<E3\t\t\t0\t2\t3\t0.5\n"
)
# No coordinates: lengths only, and two plants.
TOPOLOGY = HEAD + "Length\tREAL\nMTG:\nENTITY-CODE\t\tLength\n" + "/P1/E1\t\t2\n" + "\t+E2\t1\n" + "^<E3\t\t0.5\n" + "/P2/E1\n"


def skeleton(text):
    return LSystem.from_text(mtg_grammar_text(parse_mtg_graph(text))).derive().skeleton()


def test_coordinates_are_the_tops_of_the_entities():
    s = skeleton(POINTS)
    # drawn depth first: E1, its branch E2, then E3 that follows E1
    assert np.allclose(s.end, [[0, 0, 3], [4, 0, 6], [0, 2, 3]])
    assert np.allclose(s.start, [[0, 0, 0], [0, 0, 3], [0, 0, 3]])
    assert s.parent.tolist()[1:] == [0, 0] and s.order.tolist() == [0, 1, 0]


def test_diameters_give_the_widths():
    s = skeleton(POINTS)
    # E1 has no parent: its base is its own top diameter; E2 and E3 start with E1's top (0.8)
    assert np.allclose(s.base_radius, [0.4, 0.4, 0.4])


def test_without_coordinates_the_default_geometry_is_used():
    s = skeleton(TOPOLOGY)
    a, d = math.radians(BRANCH_ANGLE), math.radians(DIVERGENCE)
    branch = np.array([0, 0, 2]) + [math.sin(a) * math.sin(d), math.sin(a) * math.cos(d), math.cos(a)]
    assert np.allclose(s.end, [[0, 0, 2], branch, [0, 0, 2.5], [PLANT_SPACING, 0, 1]])


def test_a_latin1_mtg_file_opens_as_a_plant(tmp_path):
    path = tmp_path / "hêtre.mtg"
    path.write_bytes(TOPOLOGY.replace("Length\tREAL", "Length\tREAL\nnom\tALPHA").encode("latin-1"))
    path.write_bytes(path.read_bytes().replace(b"/P2/E1", "/P2/E1\t\t\thêtre".encode("latin-1")))
    s = LSystem.from_file(path).derive().skeleton()
    assert len(s) == 4 and np.allclose(s.end[3], [PLANT_SPACING, 0, 1])


def test_a_misread_mtg_is_a_grammar_file_error(tmp_path):
    from ramure.lsys.architecture.mtg import MTGError

    path = tmp_path / "bad.mtg"
    path.write_text(TOPOLOGY.replace("/P2/E1", "/P2/X1"))
    with pytest.raises(MTGError, match="line 17: class 'X'"):
        LSystem.from_file(path)


def test_an_mtg_written_with_geometry_rebuilds_the_same_plant(tmp_path):
    import ramure
    from ramure.lsys.architecture.amap import architecture
    from ramure.lsys.architecture.mtg import parse_mtg, write_mtg

    derivation = ramure.derive("amap/massart", n=3)
    original = derivation.skeleton()
    arch = architecture(derivation)
    path = write_mtg(arch, tmp_path / "massart.mtg", original)
    graph = parse_mtg_graph(path.read_text())
    assert {"XX", "YY", "ZZ", "TopDiameter", "BottomDiameter", "Length"} <= set(graph.feature_types)
    again = LSystem.from_file(path).derive().skeleton()
    assert len(again) == len(original) == 27
    for a, b in ((original.start, again.start), (original.end, again.end)):
        assert np.allclose(np.sort(a, axis=0), np.sort(b, axis=0))
    assert np.allclose(np.sort(original.base_radius), np.sort(again.base_radius))
    assert parse_mtg(path.read_text()).equals(arch)  # Ramure's own reader still reads it back
