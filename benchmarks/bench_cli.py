"""Start-up cost of the ``ramure`` command line: README commands, each in a fresh process.

A small job should answer quickly: each record holds the median wall time (``seconds``) and
the median CPU time of the child process (``cpu_seconds``: user + system, read with
``resource.getrusage(RUSAGE_CHILDREN)``, so a loaded machine inflates it less than the
wall time).  Targets are on CPU seconds, about 1.5 times the figures
of an idle machine: regression guards, not goals.  Everything runs in a temporary folder; the
analysed study is simulated first (not timed).

Reference (2 loaded cores, before the cuts of the cli-latency work -> after):
``check`` 0.32 s, ``study anova`` 1.72 -> 0.34 s, ``study analyze`` 5.3 -> ~4 s CPU.
Participant-level statistics (statsmodels' import, mixed and ordinal models, two more figures)
took ``study analyze`` from 2.9 to 5.5 s CPU on a 20-participant study (same loaded machine).
"""

from __future__ import annotations

import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time

TABLE = "group\tvalue\na\t1\na\t2\na\t3\nb\t4\nb\t5\nb\t7\n"


def _cli(argv, cwd):
    """(wall, cpu) seconds of one ``python -m ramure.app.cli argv`` run in ``cwd``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "ramure.app.cli", *argv], cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise RuntimeError(f"ramure {' '.join(argv)} failed: {done.stderr.strip()[-300:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _measure(argv, target_cpu, repeats=3, setup=None):
    with tempfile.TemporaryDirectory() as folder:
        cwd = pathlib.Path(folder)
        (cwd / "table.tsv").write_text(TABLE, encoding="utf-8")
        if setup:
            _cli(setup, cwd)
        runs = [_cli(argv, cwd) for _ in range(repeats)]
    wall = statistics.median(w for w, _ in runs)
    cpu = statistics.median(c for _, c in runs)
    return {
        "command": "ramure " + " ".join(argv),
        "seconds": round(wall, 3),
        "cpu_seconds": round(cpu, 3),
        "target_cpu_seconds": target_cpu,
        "ok": cpu <= target_cpu,
        "repeats": repeats,
        "load_average": round(os.getloadavg()[0], 2),
    }


def bench_check():
    return _measure(["check", "honda_sympodial"], target_cpu=0.6)


def bench_study_anova():
    return _measure(["study", "anova", "table.tsv"], target_cpu=0.6)


def bench_derive_json():
    return _measure(["derive", "honda_sympodial", "--json"], target_cpu=2.5)


def bench_fruit_json():
    return _measure(["fruit", "--preset", "round_tomato", "--json"], target_cpu=2.5)


def bench_render():
    return _measure(["render", "fruit_tree", "-o", "plant.png", "--view", "iso"], target_cpu=5.0, repeats=2)


def bench_study_analyze():
    simulate = ["study", "simulate", "--participants", "20", "--grammars", "3", "--db", "study.db"]
    return _measure(["study", "analyze", "study.db", "-o", "report"], target_cpu=6.0, repeats=2, setup=simulate)
