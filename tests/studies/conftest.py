"""Shared fixtures for the studies tests."""
from __future__ import annotations

import pytest

from ramure.studies.picks import lattice_picks
from ramure.studies.storage import Study


class FakeClock:
    """A monotonic clock the test moves by hand."""

    def __init__(self):
        self.now = 1000.0

    def __call__(self):
        return self.now

    def advance(self, seconds):
        self.now += seconds


@pytest.fixture
def clock():
    return FakeClock()


@pytest.fixture
def study(tmp_path, clock):
    s = Study.create(tmp_path / "study.db", clock=clock, name="test-study",
                     grammars={"honda": lattice_picks(seed=1), "tree2": lattice_picks(seed=2)})
    yield s
    s.close()


def complete(session, partition=None):
    """Answer every question of ``session`` with a fixed pattern, then finish."""
    partition = partition or [list(range(1, 10)), list(range(10, 19)), list(range(19, 27)), [27]]
    session.set_groups(partition)
    for label, images in enumerate(partition, start=1):
        if len(images) > 1:
            session.set_representative(label, images[0])
            session.rate(label, representative=3)
        session.rate(label, usefulness=1 + label % 4, difference=4 - label % 4)
        session.add_qualifier(label, "petit" if label == 1 else "Dense")
    session.finish()
