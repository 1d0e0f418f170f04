"""A new process answers a small job without loading what only big plants or other features need
(issue 34, a fast first call): no numba for a small plant's turtle, no networkx for a cut (the
tree's own recursion finds it), no numpy.random for a grammar that draws nothing, no numpy.ma
(numpy 2's ``np.unique`` imports it)."""

import json
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]

_RUN = """
import json, sys
from ramure.app.cli import main
main(sys.argv[1:])
heavy = ("numba", "networkx", "numpy.random", "numpy.ma")
print(json.dumps({name: name in sys.modules for name in heavy}))
"""


def _run(*argv):
    done = subprocess.run([sys.executable, "-c", _RUN, *argv], capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    result, loaded = (json.loads(line) for line in done.stdout.strip().splitlines()[-2:])
    return result, loaded


def test_derive_and_draw_a_small_plant_load_nothing_heavy():
    result, loaded = _run("derive", "honda_sympodial", "--json")
    assert (result["modules"], result["segments"]) == (11253, 1023)
    assert loaded == {"numba": False, "networkx": False, "numpy.random": False, "numpy.ma": False}


def test_a_small_regrow_loads_nothing_heavy():
    select = ",".join(str(12157 + 12 * k) for k in range(10))
    argv = ["regen", "grammars/honda_sympodial.lsys", "--select", select, "--rho", "50", "--set", "a2=25", "--json"]
    result, loaded = _run(*argv)
    assert result["min_roots"] == [6077, 6082, 6089, 6094, 6101, 6106, 6113, 6118, 6125, 6130]
    assert result["removed_modules"] == result["added_modules"] == 120 and result["cut_value"] == 21493.0
    assert loaded == {"numba": False, "networkx": False, "numpy.random": False, "numpy.ma": False}


def test_a_stochastic_grammar_draws_as_before(monkeypatch):
    # the generator is made on first use: the same draws as numpy's default_rng(seed) made at once
    import numpy as np

    from ramure.lsys import LSystem
    from ramure.lsys.engine import derive
    from ramure.lsys.regeneration import regen
    from ramure.lsys.regeneration.regen import Session

    drawn = "n: 4\nw: A(1)\np:\n  A(x) -> F(uniform(0.5, 1.5))[+(normal(30, 5))A(x)]A(x + 1)\n"

    def grown(name):
        s = Session(LSystem.from_text(drawn) if name == "drawn" else LSystem.from_file(name), seed=3)
        s.regrow(s.tree.leaves[len(s.tree.leaves) // 2 :][:5], rho=0.5, seed=11)
        return s.derivation.to_string(), s.tree.params[: s.tree.size].copy()

    for name in ("stochastic_plant", "branche_stochastic", "apricot_tree", "drawn"):
        lazy = grown(name)
        with monkeypatch.context() as m:
            m.setattr(derive, "seeded_generator", np.random.default_rng)
            m.setattr(regen, "seeded_generator", np.random.default_rng)
            eager = grown(name)
        assert lazy[0] == eager[0]
        np.testing.assert_array_equal(lazy[1], eager[1])
    _, loaded = _run("derive", "stochastic_plant", "--seed", "3", "--json")
    assert loaded["numpy.random"] is True
