"""The explorer model opens L-Py models (only when allowed to run their code) and OpenAlea MTGs."""

from __future__ import annotations

import json
import pathlib

import pytest

from ramure.app.document import CodeNotAllowed, CodeTrust, open_document, runs_code, session_runs_code
from ramure.app.model import Explorer
from ramure.lsys.readers.lpy import LpyLSystem
from ramure.lsys.regeneration.regen import Session

MODEL = """\
extern(k=2)
Axiom: A(1)
derivation length: 3
production:
A(x) :
  produce F(x)[+A(x*k)]A(x+1)
endlsystem
"""

MTG = """\
CLASSES:
SYMBOL\tSCALE\tDECOMPOSITION\tINDEXATION\tDEFINITION
$\t0\tFREE\tFREE\tIMPLICIT
P\t1\tFREE\tFREE\tIMPLICIT
E\t2\tFREE\tFREE\tIMPLICIT

DESCRIPTION:
LEFT\tRIGHT\tRELTYPE\tMAX

FEATURES:
NAME\tTYPE
Length\tREAL
Species\tALPHA

MTG:
ENTITY-CODE\t\t\tLength\tSpecies
/P1/E1\t\t\t2\tHêtre
^<E2\t\t\t3
\t+E3\t\t1
"""


@pytest.fixture
def files(tmp_path: pathlib.Path) -> dict[str, pathlib.Path]:
    model = tmp_path / "model.lpy"
    model.write_text(MODEL)
    mtg = tmp_path / "plant.mtg"
    mtg.write_bytes(MTG.encode("latin-1"))  # OpenAlea's files are often Latin-1
    return {"lpy": model, "mtg": mtg}


def test_an_lpy_is_refused_until_its_code_may_run(files: dict[str, pathlib.Path], tmp_path: pathlib.Path) -> None:
    marker = tmp_path / "ran"
    files["lpy"].write_text(f"open({str(marker)!r}, 'w').close()\n" + MODEL)
    with pytest.raises(CodeNotAllowed, match="model.lpy is an L-Py model, a Python program"):
        Explorer(files["lpy"])
    with pytest.raises(CodeNotAllowed):
        Explorer(str(files["lpy"]))  # a string path, too
    assert not marker.exists()  # refused before a line of it ran
    ex = Explorer(files["lpy"], run_code=True)
    assert marker.exists()
    assert isinstance(ex.lsystem, LpyLSystem)
    # F(1)[+A(2)]A(2) -> ... three steps: 1 + 2 + 4 = 7 F modules
    assert ex.derivation.to_string().count("F") == 7
    assert ex.path == files["lpy"]


def test_open_grammar_keeps_the_plant_when_refused(files: dict[str, pathlib.Path]) -> None:
    ex = Explorer("n: 1\nw: F")
    with pytest.raises(CodeNotAllowed) as err:
        ex.open_grammar(files["lpy"])
    assert err.value.folder == files["lpy"].parent.resolve()
    assert ex.derivation.to_string() == "F"
    ex.open_grammar(files["lpy"], run_code=True)
    assert ex.derivation.to_string().startswith("F(1)[+F(2)")


def test_an_mtg_opens_as_an_unsaved_grammar(files: dict[str, pathlib.Path]) -> None:
    ex = Explorer(files["mtg"])
    assert ex.path is None  # Save asks where to write the grammar: the MTG is never overwritten
    assert len(ex.skeleton) == 3  # E1, E2 and the branch E3
    assert sorted(ex.skeleton.length.round(6).tolist()) == [1.0, 2.0, 3.0]
    assert ex.session.filename is None


def test_code_trust_is_per_folder(tmp_path: pathlib.Path) -> None:
    trust = CodeTrust([3, "", None])  # what a settings file may hold that is not a folder
    assert trust.folders == []
    assert runs_code(tmp_path / "a.LPY") and not runs_code(tmp_path / "a.l")
    assert not trust.allows(tmp_path / "a.lpy")
    trust.allow(tmp_path / "a.lpy")
    trust.allow(tmp_path / "b.lpy")
    assert trust.folders == [str(tmp_path.resolve())]
    assert trust.allows(tmp_path / "b.lpy")
    assert not trust.allows(tmp_path / "sub" / "b.lpy")


def test_a_session_of_an_lpy_round_trips(files: dict[str, pathlib.Path], tmp_path: pathlib.Path) -> None:
    ex = Explorer(files["lpy"], run_code=True)
    ex.set_constant("k", 3.0)
    current = ex.session.current_lsystem()
    assert isinstance(current, LpyLSystem)
    assert current.constants["k"] == 3.0 and ex.lsystem.constants["k"] == 2.0
    assert current.derive().to_string() == ex.derivation.to_string()
    out = ex.save_session(tmp_path / "s.json")
    assert json.loads(out.read_text())["reader"] == ".lpy"
    assert session_runs_code(out)
    again = Explorer("n: 1\nw: F")
    with pytest.raises(CodeNotAllowed, match="s.json is a session of an L-Py model"):
        again.load_session(out)
    again.load_session(out, run_code=True)
    assert isinstance(again.lsystem, LpyLSystem)
    assert again.derivation.to_string() == ex.derivation.to_string()
    assert "A(9)" in again.derivation.to_string()  # k = 3 kept: 1 * 3 * 3


def test_a_session_of_an_lpy_without_a_file_name_round_trips() -> None:
    session = Session(LpyLSystem(MODEL), n=2)
    data = json.loads(json.dumps(session.to_dict()))
    back = Session.from_dict(data)  # no folder: no file is read, the reader is still L-Py's
    assert isinstance(back.lsystem, LpyLSystem)
    assert back.derivation.to_string() == session.derivation.to_string()


def test_a_session_of_an_mtg_plant_round_trips(files: dict[str, pathlib.Path], tmp_path: pathlib.Path) -> None:
    _, lsystem, _ = open_document(files["mtg"])
    session = Session(lsystem, filename=str(files["mtg"]))
    out = session.save(tmp_path / "m.json")
    assert not session_runs_code(out)
    assert Session.load(out).derivation.to_string() == session.derivation.to_string()


def test_saving_an_lpy_writes_n_and_externs(files: dict[str, pathlib.Path], tmp_path: pathlib.Path) -> None:
    ex = Explorer(files["lpy"], run_code=True)
    ex.set_derivation(n=4)
    ex.set_constant("k", 3.0)
    out = ex.save_grammar(tmp_path / "saved.lpy")
    text = out.read_text()
    assert "extern(k=3)" in text and "derivation length: 4" in text
    again = Explorer(out, run_code=True)
    assert again.derivation.to_string() == ex.derivation.to_string()
    assert not ex.dirty


def test_a_missing_lpy_is_said_missing(tmp_path: pathlib.Path) -> None:
    from ramure.lsys import GrammarError

    with pytest.raises(GrammarError, match="no such file"):
        Explorer(tmp_path / "gone.lpy")
