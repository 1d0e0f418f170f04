"""The study readers under fuzz (issue 37): study databases, synonym files, exploration folders.

3,000 inputs round the three readers (``tests/hardening/fuzz_studies.py``): no exception but
Ramure's own, no read command that changes a study's bytes, no input over 5 s.
"""

from __future__ import annotations

import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

INPUTS = 3000


def bench_study_readers_fuzz():
    from tests.hardening.fuzz_studies import campaign

    start = time.perf_counter()
    counts = campaign(INPUTS, seed=0)
    seconds = time.perf_counter() - start
    figures = {f"{reader}_{outcome}": n for (reader, outcome), n in sorted(counts.items())}
    bad = sum(n for (_, outcome), n in counts.items() if outcome not in ("ok", "refused"))
    return dict(seconds=round(seconds, 1), inputs=INPUTS, bad=bad, ok=bad == 0, **figures)
