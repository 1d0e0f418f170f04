"""One spelling for a parameter combination (issue 20): {"rule": r or None, "constants": {...}}."""

import json

import numpy as np
import pytest

from ramure.errors import ValueRefused
from ramure.lsys import LSystem
from ramure.lsys.engine.combination import combination, split
from ramure.lsys.regeneration.regen import Session

TEXT = "#define k 2\n#define j 3\nn: 2\nw: A(1)B(1)\np:\n A(x) -> A(x*k)\n B(x) -> B(x*k+j)\n"


def test_derive_takes_the_combination():
    ls = LSystem.from_text(TEXT)
    assert ls.derive(params=combination(None, {"k": 3})).to_string() == ls.derive(constants={"k": 3}).to_string()
    assert ls.derive(params=combination(None, {"k": 3})).to_string() == "A(9)B(21)"
    assert ls.derive(params={"rule": 1, "constants": {"k": 3}}).to_string() == "A(4)B(21)"  # B only
    assert ls.derive(params={"rule": 0, "constants": {"j": 0}}).to_string() == ls.derive().to_string()
    d = ls.derive(params={"rule": 1, "constants": {"k": 3}})
    assert d.params == {"rule": 1, "constants": {"k": 3}}
    with pytest.raises(TypeError):
        ls.derive(rule_constants={1: {"k": 3}})  # the second spelling is gone


def test_bad_combinations_are_refused_in_one_line():
    ls = LSystem.from_text(TEXT)
    for bad in ([1], {"rule": "x", "constants": {}}, {"rule": 1, "constants": {"k": "big"}}, {"rule": 1, "constants": [1]}):
        with pytest.raises(ValueRefused, match="combination"):
            ls.derive(params=bad)
    with pytest.raises(Exception, match="unknown constant"):
        ls.derive(params={"rule": 1, "constants": {"zz": 1}})
    assert split({"rule": 2}) == ({}, {2: {}})


def test_sweep_variant_session_and_old_session_files_agree(tmp_path):
    from ramure.metrics import VariantSweep

    sweep = VariantSweep(n=2, n_jobs=1, cache=False).fit(LSystem.from_text(TEXT))
    i = int(np.flatnonzero(sweep.rules_ == 1)[-1])
    combo = sweep.combination(i)
    direct = LSystem.from_text(TEXT).derive(params=combo).to_string()
    assert sweep.derive(i).to_string() == direct
    s = Session(LSystem.from_text(TEXT), n=2)
    s.regrow([], params=combo)
    assert s.derivation.to_string() == direct
    # a session file written before this change (same "params" form) loads and replays
    path = tmp_path / "s.json"
    s.save(path)
    doc = json.loads(path.read_text())
    assert doc["edits"][0]["params"] == {"rule": 1, "constants": combo["constants"]}
    assert Session.load(path).derivation.to_string() == direct
