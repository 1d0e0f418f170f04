"""apply_qualifier on the whole plant when no variant changes it: a reason, not a TypeError.

Found by type-checking the unannotated helpers: the message sorted the rule set, which is None
when nothing is selected.
"""

import numpy as np

from ramure.errors import RamureError

from ramure.lsys.regeneration.regen import Session
from ramure.metrics import VariantSweep
from ramure.metrics.apply import apply_qualifier
from ramure.metrics.qualifiers import QualifierModel


def test_no_changing_variant_on_the_whole_plant_is_reported(monkeypatch):
    sweep = VariantSweep(n=2, n_jobs=1, cache=False).fit("honda_sympodial")
    session = Session("honda_sympodial", n=2)
    monkeypatch.setattr(QualifierModel, "rank", lambda self, key, rules=None: np.zeros(0, np.int64))
    monkeypatch.setattr(Session, "set_steps", lambda self, n, params=None: (_ for _ in ()).throw(RamureError("too big")))
    out = apply_qualifier(session, "tall", sweep)
    assert not out.improved and out.tried == 0 and out.regen is None
    assert "ascension 1: no variant changes the plant" in out.reason
    assert "no other derivation count could be derived" in out.reason
    assert len(session.edits) == 0
