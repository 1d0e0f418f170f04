"""The desktop's command line takes a grammar file or a shipped grammar's name, from any directory."""

import pytest

import ramure.grammars
from ramure.app.desktop import launch
from ramure.errors import RamureError


def test_an_unknown_grammar_is_refused_in_one_line(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert launch.main(["no_such_grammar"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "ramure desktop: no grammar file or shipped grammar named 'no_such_grammar' "
        "(ramure.grammars.names() lists the shipped ones)"
    ]


@pytest.mark.parametrize("given", ["honda_sympodial", "grammars/honda_sympodial.lsys"])
def test_a_shipped_name_opens_the_shipped_file(given, capsys, tmp_path, monkeypatch):
    seen = []

    class Stop(RamureError):
        pass

    def explorer(source, n=None, seed=0, run_code=False):
        seen.append((source, run_code))
        raise Stop("stop here")

    monkeypatch.chdir(tmp_path)  # not the repository: the name must resolve through the package
    monkeypatch.setattr("ramure.app.model.Explorer", explorer)
    assert launch.main([given]) == 2
    assert seen == [(ramure.grammars.path("honda_sympodial"), True)]  # named on the command line: runs as derive does
    assert "stop here" in capsys.readouterr().err
