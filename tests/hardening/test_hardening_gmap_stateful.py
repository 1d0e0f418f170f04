"""A stateful property test of the 3G-map kernel (issue 37, "the harness"): Hypothesis picks a
sequence of operations (add prisms, sew and unsew faces, split edges, faces, prisms, remove
volumes) with arguments that are often wrong; after each accepted operation the map is valid,
after each refused one (a RamureError) it is byte-identical.  Builds on the fixed-seed run of
``test_hardening_gmap_kernel.py``; the kernel is imported from ``ramure.gmap`` only."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, invariant, precondition, rule

from ramure.errors import RamureError
from ramure.gmap import GMap3
from tests.hardening.test_hardening_gmap_kernel import state

#: The map stops growing past this many darts (each step stays fast).
MAX_DARTS = 6000
ORDERS = st.sampled_from([3, 4, 5, 6, 2, 0, -1, 40000])


class KernelMachine(RuleBasedStateMachine):
    def __init__(self) -> None:
        super().__init__()
        self.gm = GMap3()
        self.gm.add_prisms(4, 2, origins=[[0, 0, 0], [0, 0, 1]])
        self.accepted = self.refused = 0

    def attempt(self, call) -> None:
        before = state(self.gm)
        try:
            call()
        except RamureError:
            self.refused += 1
            assert state(self.gm) == before, "a refused operation changed the map"
            return
        self.accepted += 1
        assert self.gm.is_valid(), self.gm.validity_problems()[:3]

    def dart(self, data, wrong: bool = True) -> int:
        """A dart id: mostly one of the map's, sometimes just outside it."""
        n = self.gm.n_darts
        if wrong and data.draw(st.integers(0, 9)) == 0:
            return data.draw(st.sampled_from([-1, -7, n, n + 3, 2**40]))
        return data.draw(st.integers(0, max(n - 1, 0)))

    def volume(self, data) -> int:
        return data.draw(st.integers(-1, self.gm.n_volumes))

    @precondition(lambda self: self.gm.n_darts < MAX_DARTS)
    @rule(order=ORDERS, count=st.integers(0, 3))
    def add_prisms(self, order, count):
        self.attempt(lambda: self.gm.add_prisms(order, count, origins=np.arange(count)[:, None] * [0.0, 0.0, 1.0]))

    @rule(data=st.data())
    def sew_end_to_start(self, data):
        """Sew a prism's E face onto another's O face: the well-formed sew (refused when taken)."""
        gm = self.gm
        a, b = self.volume(data), self.volume(data)
        if not (0 <= a < gm.n_volumes and 0 <= b < gm.n_volumes):
            return
        try:
            top, bottom = gm.face_of(a, "E"), gm.face_of(b, "O")
        except RamureError:
            return
        self.attempt(lambda: gm.sew3([int(top)], [int(bottom)]))

    @rule(data=st.data())
    def sew_any(self, data):
        self.attempt(lambda: self.gm.sew3([self.dart(data)], [self.dart(data)]))

    @rule(data=st.data())
    def unsew(self, data):
        self.attempt(lambda: self.gm.unsew3([self.dart(data)]))

    @precondition(lambda self: self.gm.n_darts < MAX_DARTS)
    @rule(data=st.data(), t=st.sampled_from([0.5, 0.25, 0.0, 1.0, float("nan")]))
    def split_edge(self, data, t):
        self.attempt(lambda: self.gm.split_edge([self.dart(data)], t))

    @precondition(lambda self: self.gm.n_darts < MAX_DARTS)
    @rule(data=st.data())
    def split_face(self, data):
        self.attempt(lambda: self.gm.split_face(self.dart(data), self.dart(data)))

    @precondition(lambda self: self.gm.n_darts < MAX_DARTS)
    @rule(data=st.data(), steps=st.lists(st.integers(-1, 4), min_size=1, max_size=3))
    def split_faces(self, data, steps):
        darts = [self.dart(data) for _ in range(data.draw(st.integers(len(steps) - 1, len(steps))) or 1)]
        self.attempt(lambda: self.gm.split_faces(darts, steps))

    @precondition(lambda self: self.gm.n_darts < MAX_DARTS)
    @rule(data=st.data(), t=st.sampled_from([0.5, 0.3, 0.0, 1.5]))
    def split_prism(self, data, t):
        self.attempt(lambda: self.gm.split_prism(self.volume(data), t))

    @precondition(lambda self: self.gm.n_darts < MAX_DARTS)
    @rule(data=st.data())
    def split_prisms(self, data):
        volumes = data.draw(st.lists(st.integers(-1, self.gm.n_volumes), min_size=1, max_size=3))
        self.attempt(lambda: self.gm.split_prisms(volumes, 0.5))

    @rule(data=st.data())
    def remove_volumes(self, data):
        volumes = data.draw(st.lists(st.integers(-1, self.gm.n_volumes), max_size=2))
        self.attempt(lambda: self.gm.remove_volumes(volumes))

    @invariant()
    def darts_belong_to_volumes(self):
        volume = np.asarray(self.gm.dart_data["volume"])
        assert len(volume) == self.gm.n_darts
        assert not len(volume) or (volume.min() >= 0 and volume.max() < self.gm.n_volumes)


KernelMachine.TestCase.settings = settings(
    max_examples=60,
    stateful_step_count=25,
    deadline=None,
    derandomize=True,  # the same sequences on every run: make test stays reproducible
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
TestKernelMachine = KernelMachine.TestCase


def test_the_machine_exercises_both_outcomes():
    """One fixed run of the machine by hand: refusals and acceptances both happen, so the
    invariants above are checked on both paths."""
    import random

    machine = KernelMachine()
    rng = random.Random(5)
    gm = machine.gm
    for _ in range(40):
        a, b = rng.randrange(-2, gm.n_darts + 2), rng.randrange(0, gm.n_darts)
        machine.attempt(lambda a=a, b=b: gm.split_face(a, b))
        machine.attempt(lambda a=a: gm.split_edge([a], 0.5))
    assert machine.accepted > 5 and machine.refused > 5
