"""The load benchmark's crowd, small and bounded, in ``make test`` (issue 38, section 5):
simulated participants answering at once against ``ramure study serve`` on 127.0.0.1, on SQLite
and on PostgreSQL.  Nothing acknowledged may be lost; the figures are reported as the benchmark
reports them (``benchmarks/bench_web_study.py`` runs 200 participants).
"""

from __future__ import annotations

import importlib.util
import pathlib

import pytest

pytest.importorskip("httpx")
pytest.importorskip("uvicorn")

BENCH = pathlib.Path(__file__).resolve().parents[2] / "benchmarks" / "bench_web_study.py"


def bench():
    spec = importlib.util.spec_from_file_location("bench_web_study", BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.timeout(400)
@pytest.mark.parametrize("backend", ["sqlite", "postgresql"])
def test_a_crowd_answering_at_once_loses_no_acknowledged_answer(backend, request):
    if backend == "postgresql":
        request.getfixturevalue("pg_cluster")  # skipped, with its reason, where PostgreSQL is absent
    figures = bench().load(kill=False, backend=backend, participants=12)
    print(figures)
    assert figures["backend"] == backend
    # every answer of every participant acknowledged: 16 in the set, 4 pages (instructions,
    # practice, attention check, demographics)
    assert figures["answers"] == 12 * (16 + 4)
    assert figures["answers_lost"] == 0 and figures["tests_finished"] == 12
    assert figures["answers_per_second"] > 0 and 0 < figures["p50_latency_ms"] <= figures["p95_latency_ms"]
