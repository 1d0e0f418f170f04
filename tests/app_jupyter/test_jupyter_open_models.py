"""The notebook explorer opens L-Py models only with run_code=True, and OpenAlea MTGs."""

from __future__ import annotations

import pytest

from ramure.app.document import CodeNotAllowed
from ramure.app.jupyter import NotebookExplorer as Explorer

MODEL = "Axiom: A(1)\nderivation length: 2\nproduction:\nA(x) --> F(x)[+A(x+1)]A(x+1)\nendlsystem\n"
MTG = (
    "CLASSES:\nSYMBOL\tSCALE\tDECOMPOSITION\tINDEXATION\tDEFINITION\n$\t0\tFREE\tFREE\tIMPLICIT\n"
    "P\t1\tFREE\tFREE\tIMPLICIT\nE\t2\tFREE\tFREE\tIMPLICIT\n\nDESCRIPTION:\nLEFT\tRIGHT\tRELTYPE\tMAX\n\n"
    "FEATURES:\nNAME\tTYPE\n\nMTG:\nENTITY-CODE\n/P1/E1\n^<E2\n^<E3\n"
)


def test_an_lpy_needs_run_code(tmp_path):
    path = tmp_path / "m.lpy"
    path.write_text(MODEL)
    with pytest.raises(CodeNotAllowed, match="pass run_code=True to Explorer"):
        Explorer(path, view="static", size=(120, 120), cache=False)
    ex = Explorer(path, view="static", size=(120, 120), cache=False, run_code=True)
    assert ex.plant.to_string() == "F(1)[+F(2)[+A(3)]A(3)]F(2)[+A(3)]A(3)"
    ex.save(tmp_path / "s.json")
    other = Explorer("n: 1\nw: F", view="static", size=(120, 120), cache=False)
    other.load_session(tmp_path / "s.json")  # refused on the message line, the plant kept
    assert "pass run_code=True to load_session" in other.message.widget.value
    assert other.plant.to_string() == "F"
    other.load_session(tmp_path / "s.json", run_code=True)
    assert other.plant.to_string() == ex.plant.to_string()


def test_an_mtg_opens_as_a_plant(tmp_path):
    path = tmp_path / "chain.mtg"
    path.write_text(MTG)
    ex = Explorer(str(path), view="static", size=(120, 120), cache=False)
    assert len(ex.skeleton) == 3  # OpenAlea's chain of three entities, one segment each
    assert ex.skeleton.end[:, 2].round(6).tolist() == [1.0, 2.0, 3.0]  # DEFAULT_LENGTH upright
