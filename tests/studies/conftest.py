"""Shared fixtures for the studies tests."""

from __future__ import annotations

import pytest
from pg_cluster import Cluster, why_not

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
    s = Study.create(
        tmp_path / "study.db",
        clock=clock,
        name="test-study",
        grammars={"honda": lattice_picks(seed=1), "tree2": lattice_picks(seed=2)},
    )
    yield s
    s.close()


@pytest.fixture(scope="session")
def pg_cluster():
    """A throwaway PostgreSQL server (Debian's package) for the session's PostgreSQL tests."""
    reason = why_not()
    if reason:
        pytest.skip(reason)
    cluster = Cluster(fsync=False).start()
    yield cluster
    cluster.stop()


@pytest.fixture
def pg_url(pg_cluster):
    """The URL of a new, empty database on :func:`pg_cluster`."""
    return pg_cluster.new_database()
