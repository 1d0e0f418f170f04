"""``explore()`` takes the sweep's own keyword set (issue 41): it declares none of them again,
passes every one through, and refuses one the sweep does not have."""

from __future__ import annotations

import inspect

import pytest

from ramure.errors import ValueRefused
from ramure.metrics.exploration import explore
from ramure.metrics.sweep import VariantSweep

GRAMMAR = "honda_sympodial"


def test_explore_declares_no_sweep_keyword_again():
    sweep = set(inspect.signature(VariantSweep).parameters)
    assert len(sweep) == 15  # the 13 the issue counted, "wide" and "hidden" (issue 35: ±25 %, literals)
    assert set(inspect.signature(explore).parameters) & sweep == set()


def test_every_sweep_keyword_reaches_the_sweep(tmp_path):
    exp = explore(GRAMMAR, n=2, seed=3, beta=0.2, mode="lhs", n_samples=4, n_jobs=1, cache=False, connect_timeout=5.0)
    s = exp.sweep
    assert (s.n, s.seed, s.beta, s.mode, s.n_samples, s.connect_timeout) == (2, 3, 0.2, "lhs", 4, 5.0)
    assert s.n_variants_ == 4 * s.n_rules_  # lhs: --samples per rule
    assert exp.picks.variant.shape == (27,)


def test_a_keyword_the_sweep_does_not_have_is_refused():
    with pytest.raises(ValueRefused, match="no parameter 'samples'"):
        explore(GRAMMAR, n=2, samples=4)
    with pytest.raises(ValueRefused, match=r"sweep options \(n\), not both"):
        explore(GRAMMAR, sweep=VariantSweep(n=2), n=3)
