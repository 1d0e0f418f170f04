"""The explorer model opens a shipped grammar by name, as ramure.load does."""

import ramure
from ramure.app.model import Explorer


def test_explorer_opens_a_shipped_grammar_by_name():
    by_name = Explorer("honda_sympodial")
    assert by_name.error is None and by_name.path is not None and by_name.path.name == "honda_sympodial.lsys"
    expected = ramure.derive("honda_sympodial")
    assert by_name.derivation.n == expected.n == 10
    assert len(by_name.derivation.tree.leaves) == len(expected.tree.leaves) == 11253
    assert by_name.text == by_name.path.read_text(encoding="utf-8")
