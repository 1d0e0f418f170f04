"""Shared helpers for the benchmark modules (importable because run.py's folder is on sys.path)."""

from __future__ import annotations

import time


def best(fn, repeats: int = 3):
    """Best wall time of ``repeats`` calls of ``fn()`` and the last call's result."""
    fastest, out = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        fastest = min(fastest, time.perf_counter() - t0)
    return fastest, out


def child_json(out) -> dict:
    """The last JSON line a finished child process (``subprocess.run`` result) printed, or
    ``{"error": ...}``: its last stderr line, when it failed or printed none."""
    import json

    lines = [line for line in out.stdout.splitlines() if line.startswith("{")]
    if out.returncode or not lines:
        return {"error": (out.stderr.strip().splitlines() or [f"exit {out.returncode}"])[-1]}
    return json.loads(lines[-1])
