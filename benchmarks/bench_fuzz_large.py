"""The large fuzz run of issue 37: 100,000 inputs across every reader's fuzzer.

The readers (``tests/hardening/fuzz_all.py``): ``.lsys`` grammars through the whole core loop
(parse, draw, measure, regrow, undo), ``.g3l`` wood grammars, study databases, synonym files
and exploration folders (``pca.json``, ``picks.json``), sessions, MTG files and the desktop's
settings file.  Each chunk of inputs runs in a process of its own under a 2 GB address-space
limit (``RLIMIT_AS``), so a memory blow-up is a ``MemoryError`` crash, not a swapping machine.

Targets: 0 exceptions other than Ramure's own errors, 0 inputs over 5 s (of CPU: on a shared
machine the wall clock counts the other jobs too) and no chunk stopped by the limit.
Before the run, each reader fuzzes a few inputs that are not counted: the first process
compiles numba's kernels (and Python's bytecode) into their on-disk caches, which is once per
installation, not work an input causes.  ``RAMURE_FUZZ_INPUTS`` sets the total (100,000 by
default; a smaller run for a quick look).
``RAMURE_FUZZ_LOG`` names a JSON-lines file where each finished chunk is appended: a run that
is stopped and started again with the same log skips the chunks already there.
"""

from __future__ import annotations

import collections
import json
import os
import pathlib
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
#: Each reader's share of the inputs.
SHARES = {"lsys": 0.4, "g3l": 0.15, "studies": 0.2, "files": 0.25}
CHUNK = 2000
#: The seed and size of the uncounted warm-up chunk of each reader.
WARM_UP = (10**6, 50)


def chunks(total: int) -> list[tuple[str, int, int]]:
    """``(reader, inputs, seed)`` for every chunk of a run of ``total`` inputs."""
    out = []
    for reader, share in SHARES.items():
        left, seed = round(total * share), 0
        while left > 0:
            out.append((reader, min(CHUNK, left), seed))
            left -= CHUNK
            seed += 1
    return out


def run_chunk(reader: str, inputs: int, seed: int) -> dict:
    """One chunk in a fresh process under the limit; its figures (or the reason it died)."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", QT_QPA_PLATFORM="offscreen")
    cmd = [sys.executable, "-m", "tests.hardening.fuzz_all", "--reader", reader, "--inputs", str(inputs), "--seed", str(seed)]
    out = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
    lines = [line for line in out.stdout.splitlines() if line.startswith("{")]
    if not lines:  # the process itself died (the limit, a signal): every input of it counts as a crash
        tail = (out.stderr.strip().splitlines() or [f"exit {out.returncode}"])[-1]
        return dict(reader=reader, seed=seed, inputs=inputs, crashes=inputs, slow=0, outcomes={"died": inputs}, died=tail)
    return json.loads(lines[-1])


def logged_chunks(log: pathlib.Path | None) -> dict[tuple[str, int, int], dict]:
    """The chunks an earlier run appended to ``log``, by ``(reader, inputs, seed)``."""
    if log is None or not log.is_file():
        return {}
    records = [json.loads(line) for line in log.read_text().splitlines() if line.strip()]
    return {(r["reader"], r["inputs"], r["seed"]): r for r in records}


def bench_fuzz_large() -> dict:
    total = int(os.environ.get("RAMURE_FUZZ_INPUTS", "100000"))
    log = pathlib.Path(os.environ["RAMURE_FUZZ_LOG"]) if os.environ.get("RAMURE_FUZZ_LOG") else None
    done = logged_chunks(log)
    start = time.perf_counter()
    for reader in SHARES:
        run_chunk(reader, WARM_UP[1], WARM_UP[0])
    per_reader: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    peak, died, records = 0.0, [], []
    for reader, inputs, seed in chunks(total):
        record = done.get((reader, inputs, seed)) or run_chunk(reader, inputs, seed)
        records.append(record)
        if log is not None and (reader, inputs, seed) not in done:
            with log.open("a") as stream:
                stream.write(json.dumps(record) + "\n")
        per_reader[reader].update(inputs=record["inputs"], crashes=record["crashes"], slow=record["slow"])
        per_reader[reader].update({f"outcome {k}": n for k, n in record["outcomes"].items()})  # "slow" is a key of both
        peak = max(peak, record.get("peak_mb", 0.0))
        if "died" in record:
            died.append(f"{reader}/{seed}: {record['died']}")
    inputs = sum(c["inputs"] for c in per_reader.values())
    crashes = sum(c["crashes"] for c in per_reader.values())
    slow = sum(c["slow"] for c in per_reader.values())
    return dict(
        seconds=round(time.perf_counter() - start, 1),
        chunk_seconds=round(sum(r.get("seconds", 0.0) for r in records), 1),
        chunks_resumed=sum(key in done for key in chunks(total)),
        inputs=inputs,
        crashes=crashes,
        slow_inputs=slow,
        peak_mb=peak,
        limit_mb=2048,
        chunks_died=died,
        readers={r: dict(c) for r, c in per_reader.items()},
        ok=bool(crashes == 0 and slow == 0 and not died and inputs >= total),
    )
