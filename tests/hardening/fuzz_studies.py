"""Fuzz the study readers: study databases, synonym files and exploration folders (issue 37).

Run from the repository root::

    python -m tests.hardening.fuzz_studies --inputs 3000            # a campaign
    python -m tests.hardening.fuzz_studies --inputs 90 --seed 1     # a slice

Inputs go round the three readers.  ``study``: a real study made by the simulator, with
random values of random types written into random cells, rows deleted, the file truncated,
or its version, application id or journal mode changed; it goes through what the read
commands do (``Study.open(readonly=True)``, ``load_study_data``, ``analyze``) and its bytes
are compared before and after.  ``synonyms``: the shipped table with values swapped for
other types, deep nesting, bytes flipped; read by ``SynonymTable.load``.  ``exploration``:
``pca.json`` and ``picks.json`` with the same mutations; read by ``read_exploration_info``
and ``load_picks``.  Outcomes: ``ok``, ``refused`` (a RamureError), ``crash:<type>`` (a
bug), ``changed`` (a read wrote to the file: a bug), ``slow`` (over 5 s).  Goal: no crash,
no change, nothing slow.
"""

from __future__ import annotations

import collections
import functools
import hashlib
import json
import pathlib
import shutil
import sqlite3
import sys
import tempfile
import time
import traceback

import numpy as np

from ramure.errors import RamureError
from tests.hardening.fuzz import reader_campaign_main

SLOW_SECONDS = 5.0
VALUES = [None, 0, -1, 1, 4, 5, 27, 28, 1000, 2**62, -(2**63), 1.5, -1e308, float("inf"), "", " ", "lots", "{}", "[1]"]
VALUES += ['{"rule": "x"}', '{"rule": 1, "constants": 5}', b"\xff\x00", "P1", "1", "../../etc/passwd", "é" * 300]


@functools.lru_cache(maxsize=1)
def _real_study() -> pathlib.Path:
    from ramure.studies.simulate import simulate_study

    path = pathlib.Path(tempfile.mkdtemp(prefix="ramure-fuzz-study-")) / "study.db"
    simulate_study(path, participants=3, grammars=2, seed=3)
    return path


@functools.lru_cache(maxsize=1)
def _cells() -> list[tuple[str, str, int]]:
    conn = sqlite3.connect(_real_study())
    cells = []
    for (table,) in conn.execute("SELECT name FROM sqlite_master WHERE type='table'"):
        columns = [r[1] for r in conn.execute(f"PRAGMA table_info({table})")]
        cells += [(table, c, r[0]) for r in conn.execute(f"SELECT rowid FROM {table}") for c in columns]
    conn.close()
    return cells


def _mutate_study(rng: np.random.Generator, path: pathlib.Path) -> None:
    shutil.copyfile(_real_study(), path)
    kind = rng.random()
    if kind < 0.06:  # truncated, or bytes flipped in the file
        data = bytearray(path.read_bytes())
        if rng.random() < 0.5:
            data = data[: int(rng.integers(1, len(data)))]
        else:
            for at in rng.integers(0, len(data), size=int(rng.integers(1, 20))):
                data[at] = int(rng.integers(256))
        path.write_bytes(bytes(data))
        return
    conn = sqlite3.connect(path)
    conn.execute("PRAGMA ignore_check_constraints = 1")
    if kind < 0.12:
        pragma = ["user_version = 0", "user_version = 1", "user_version = 3", "application_id = 7", "journal_mode = DELETE"]
        conn.execute(f"PRAGMA {pragma[int(rng.integers(len(pragma)))]}")
    elif kind < 0.16:
        table = ["events", "qualifiers", "picks", "study"][int(rng.integers(4))]
        conn.execute(f"DROP TABLE {table}")
    cells = _cells()
    for k in rng.choice(len(cells), size=int(rng.integers(1, 5)), replace=False):
        table, column, rowid = cells[k]
        try:
            if rng.random() < 0.1:
                conn.execute(f"DELETE FROM {table} WHERE rowid = ?", (rowid,))
            else:
                conn.execute(f"UPDATE {table} SET {column} = ? WHERE rowid = ?", (VALUES[int(rng.integers(len(VALUES)))], rowid))
        except sqlite3.Error:
            pass  # NOT NULL, UNIQUE, a dropped table: SQLite itself refuses the mutation
    conn.commit()
    conn.close()


def _read_study(path: pathlib.Path) -> None:
    from ramure.studies.data import load_study_data
    from ramure.studies.report import analyze
    from ramure.studies.storage import Study

    with Study.open(path, readonly=True) as study:
        study.participants(), study.tests(), study.events()
        for grammar in study.grammars:
            study.picks(grammar)
    analyze(load_study_data(path, finished_only=False))


def _mutate_json(rng: np.random.Generator, doc: object) -> bytes:
    """``doc`` with a few values swapped for others, or nested deep, or bytes flipped."""
    kind = rng.random()
    if kind < 0.1:
        depth = int(rng.integers(10, 200_000))
        return b"[" * depth + b"]" * depth
    doc = json.loads(json.dumps(doc))
    for _ in range(int(rng.integers(1, 4))):
        parent, key, node = None, None, doc
        while isinstance(node, (dict, list)) and node and rng.random() < 0.8:
            keys = list(node) if isinstance(node, dict) else list(range(len(node)))
            key = keys[int(rng.integers(len(keys)))]
            parent, node = node, node[key]
            if rng.random() < 0.3:
                break
        if parent is not None:
            value = VALUES[int(rng.integers(len(VALUES)))]
            parent[key] = value if not isinstance(value, bytes) else [[1]]
    data = bytearray(json.dumps(doc).encode())
    if kind > 0.9:
        for at in rng.integers(0, len(data), size=int(rng.integers(1, 8))):
            data[at] = int(rng.integers(256))
    return bytes(data)


def _synonyms(rng: np.random.Generator, folder: pathlib.Path) -> None:
    from importlib import resources

    from ramure.studies.qualifiers import SynonymTable

    shipped = json.loads(resources.files("ramure.studies").joinpath("synonyms.json").read_text(encoding="utf-8"))
    path = folder / "syn.json"
    path.write_bytes(_mutate_json(rng, shipped))
    table = SynonymTable.load(path)
    table.canonical("petit et pas très dense")


def _exploration(rng: np.random.Generator, folder: pathlib.Path) -> None:
    from ramure.metrics.exploration import read_exploration_info
    from ramure.studies.picks import lattice_picks, load_picks

    picks = [dict(id=p.id, variant=p.variant, pca=list(p.pca), params=p.params, image=f"p{p.id}.png") for p in lattice_picks()]
    pca = {"grammar": "honda_sympodial", "n": 4, "seed": 1, "variants": 10}
    (folder / "pca.json").write_bytes(_mutate_json(rng, pca) if rng.random() < 0.7 else json.dumps(pca).encode())
    (folder / "picks.json").write_bytes(_mutate_json(rng, picks) if rng.random() < 0.5 else json.dumps(picks).encode())
    read_exploration_info(folder)
    load_picks(folder)


def _study(rng: np.random.Generator, folder: pathlib.Path) -> str:
    path = folder / "study.db"
    _mutate_study(rng, path)
    before = hashlib.sha256(path.read_bytes()).digest(), sorted(p.name for p in folder.iterdir())
    try:
        _read_study(path)
        outcome = "ok"
    except RamureError:
        outcome = "refused"
    after = hashlib.sha256(path.read_bytes()).digest(), sorted(p.name for p in folder.iterdir())
    return outcome if after == before else "changed"


def run_one(kind: str, rng: np.random.Generator, folder: pathlib.Path) -> str:
    """One input of reader ``kind``; returns its outcome."""
    start = time.process_time()  # CPU seconds: the wall clock also counts the other jobs of a shared machine
    try:
        if kind == "study":
            outcome = _study(rng, folder)
        else:
            (_synonyms if kind == "synonyms" else _exploration)(rng, folder)
            outcome = "ok"
    except RamureError:
        outcome = "refused"
    except Exception as exc:  # noqa: BLE001 - what the fuzzer is looking for
        outcome = f"crash:{type(exc).__name__}"
        traceback.print_exc(file=sys.stderr)
    return "slow" if time.process_time() - start > SLOW_SECONDS else outcome


def campaign(inputs: int, seed: int = 0) -> collections.Counter:
    """Run ``inputs`` inputs round the three readers; counts of ``(reader, outcome)``."""
    rng = np.random.default_rng(seed)
    counts: collections.Counter = collections.Counter()
    with tempfile.TemporaryDirectory(prefix="ramure-fuzz-") as tmp:
        for i in range(inputs):
            kind = ("study", "synonyms", "exploration")[i % 3]
            folder = pathlib.Path(tmp) / str(i)
            folder.mkdir()
            counts[kind, run_one(kind, rng, folder)] += 1
            shutil.rmtree(folder, ignore_errors=True)
    return counts


def main(argv: list[str] | None = None) -> int:
    return reader_campaign_main(campaign, __doc__ or "", argv)


if __name__ == "__main__":
    sys.exit(main())
