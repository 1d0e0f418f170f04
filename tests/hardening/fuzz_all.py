"""Every reader's fuzzer in one place, each run under a 2 GB address-space limit (issue 37).

Run from the repository root::

    python -m tests.hardening.fuzz_all --reader lsys --inputs 2000 --seed 3

runs one fuzzer in this process after ``resource.setrlimit(RLIMIT_AS, 2 GB)`` and prints one
JSON line: the inputs, the outcomes, ``crashes`` (exceptions other than RamureError, and
writes by read commands), ``slow`` (over 5 s of CPU, or stopped after 30 s of CPU), the peak memory
(``VmHWM``) and the seconds.  ``benchmarks/bench_fuzz_large.py`` runs every reader this way,
in chunks, for the large run of 100,000 inputs.

The readers: ``lsys`` (grammars, through the whole core loop: :mod:`tests.hardening.fuzz`),
``g3l`` (wood grammars: :mod:`tests.hardening.fuzz_g3l`), ``studies`` (study databases,
synonym files, exploration folders: :mod:`tests.hardening.fuzz_studies`) and ``files``
(sessions, MTG files, the desktop's settings file: :mod:`tests.hardening.fuzz_files`).
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import resource
import sys
import time

#: The address-space limit each fuzzing process runs under.
LIMIT_BYTES = 2 * 2**30
READERS = ("lsys", "g3l", "studies", "files")
GOOD = ("ok", "refused")


def _outcomes(reader: str, inputs: int, seed: int) -> collections.Counter:
    """``(part, outcome)`` counts of ``inputs`` inputs of ``reader``'s fuzzer."""
    if reader == "lsys":
        from tests.hardening.fuzz import campaign

        return campaign(inputs, seed)[0]
    if reader == "g3l":
        from tests.hardening.fuzz_g3l import campaign as g3l_campaign

        return g3l_campaign(inputs, seed)[0]
    if reader == "studies":
        from tests.hardening.fuzz_studies import campaign as studies_campaign

        return studies_campaign(inputs, seed)
    from tests.hardening.fuzz_files import campaign as files_campaign

    return files_campaign(inputs, seed)


def peak_mb() -> float:
    """This process's peak resident memory (``VmHWM``), in MB."""
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    return 0.0


def run(reader: str, inputs: int, seed: int) -> dict:
    """Fuzz ``reader`` with ``inputs`` inputs under the address-space limit; the figures."""
    resource.setrlimit(resource.RLIMIT_AS, (LIMIT_BYTES, LIMIT_BYTES))
    sys.setrecursionlimit(max(sys.getrecursionlimit(), 3000))
    start = time.perf_counter()
    counts = _outcomes(reader, inputs, seed)
    outcomes: collections.Counter = collections.Counter()
    for (_, outcome), n in counts.items():
        outcomes[outcome.split(":")[0] if outcome.startswith("refused") else outcome] += n
    slow = sum(n for o, n in outcomes.items() if o in ("slow", "hang"))
    return dict(
        reader=reader,
        seed=seed,
        inputs=sum(outcomes.values()),
        crashes=sum(n for o, n in outcomes.items() if o not in GOOD and o not in ("slow", "hang")),
        slow=slow,
        outcomes=dict(sorted(outcomes.items())),
        peak_mb=round(peak_mb(), 1),
        limit_mb=resource.getrlimit(resource.RLIMIT_AS)[0] // 2**20,
        seconds=round(time.perf_counter() - start, 1),
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reader", choices=READERS, required=True)
    parser.add_argument("--inputs", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")  # the settings reader needs no display
    record = run(args.reader, args.inputs, args.seed)
    print(json.dumps(record), flush=True)
    return 1 if record["crashes"] or record["slow"] else 0


if __name__ == "__main__":
    sys.exit(main())
