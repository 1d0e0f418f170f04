"""The kernels' numba cache (issue 14, memory): where it is written, that a second process loads
the machine code without compiling and without numba's compiler registries (``ramure.jit``),
that processes compiling at the same time do not corrupt it, and that git ignores it."""

from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]

# One small kernel, in a fresh process whose numba cache is NUMBA_CACHE_DIR; prints what numba
# did (its dispatcher counts hits and misses per signature) and what got imported.
_RUN_KERNEL = """
import json, sys
import numpy as np
from ramure.jit import on_first_compile
compiled = []
on_first_compile(compiled.append)
if "--runtime-from-cache" in sys.argv:  # numba's runtime module must come from its cached machine code
    from numba.core.runtime import nrtdynmod

    def refuse(*args):
        raise AssertionError("the runtime module was compiled")

    nrtdynmod.create_nrt_module = refuse
from ramure.lsys.interpretation import _turtle_kernel as K
symbols = np.array([5, 1, 5, 1, 5, 2, 2, 5, 1, 5, 2], np.int8)   # x [ x [ x ] ] x [ x ]
match = np.empty(len(symbols), np.int32)
balanced = K.fill_bracket_pairs(symbols, 1, 2, match)
stats = K.fill_bracket_pairs.stats
registries = "numba.np.arraymath" in sys.modules
record = {"match": match.tolist(), "balanced": bool(balanced),
          "hits": sum(stats.cache_hits.values()), "misses": sum(stats.cache_misses.values()),
          "compiled": list(compiled), "registries": registries, "scipy_linalg": "scipy.linalg" in sys.modules}
if "--then-compile" in sys.argv:  # a function compiled after a light load: numba refreshes itself
    from ramure.jit import njit
    dot = njit(lambda a, b: np.dot(a, b))
    record["dot"] = float(dot(np.arange(3.0), np.arange(3.0)))
    doubled = njit(lambda n: np.arange(n) * 2.0)  # allocates and returns an array: the runtime's calls
    record["doubled"] = doubled(4).tolist()
    record["compiled_after"] = compiled
print(json.dumps(record))
"""

EXPECTED_MATCH = [-1, 6, -1, 5, -1, 3, 1, -1, 10, -1, 8]


def _run(cache_dir, *args, wait=True):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache_dir)}
    proc = subprocess.Popen(
        [sys.executable, "-c", _RUN_KERNEL, *args], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    return _result(proc) if wait else proc


def _result(proc):
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    return json.loads(out.strip().splitlines()[-1])


def test_a_second_process_loads_the_kernel_from_the_cache_without_numbas_compiler(tmp_path):
    first = _run(tmp_path)
    assert first["match"] == EXPECTED_MATCH and first["balanced"]
    assert (first["misses"], first["hits"]) == (1, 0)
    assert first["compiled"] == ["fill_bracket_pairs"]  # the "first run" notice fires on a compile
    assert first["registries"]  # compiling needs the whole compiler
    written = [p for p in tmp_path.rglob("*") if p.is_file()]
    # index and machine code of the kernel, numba's runtime module (ramure.jit), no temporary left
    assert {p.suffix for p in written} == {".nbi", ".nbc", ".bin"}
    assert all("fill_bracket_pairs" in p.name or p.name.startswith("numba_runtime-") for p in written)

    second = _run(tmp_path, "--then-compile", "--runtime-from-cache")
    assert second["match"] == EXPECTED_MATCH
    assert (second["misses"], second["hits"]) == (0, 1)
    assert second["compiled"] == []
    # the cached machine code was loaded without numba's registries (and the scipy.linalg they import)
    assert not second["registries"] and not second["scipy_linalg"]
    # a function compiled afterwards in the same process still gets the full compiler
    assert second["dot"] == 5.0 and second["doubled"] == [0.0, 2.0, 4.0, 6.0]
    assert second["compiled_after"] == ["<lambda>"]


def test_a_runtime_cache_that_does_not_load_is_compiled_again(tmp_path):
    _run(tmp_path)
    (runtime,) = tmp_path.rglob("numba_runtime-*.bin")
    runtime.write_bytes(b"not a pickle")
    again = _run(tmp_path)
    assert (again["misses"], again["hits"], again["match"]) == (0, 1, EXPECTED_MATCH)
    assert runtime.read_bytes() != b"not a pickle"  # written again, whole
    assert _run(tmp_path, "--runtime-from-cache")["match"] == EXPECTED_MATCH


def test_processes_compiling_at_the_same_time_leave_a_usable_cache(tmp_path):
    procs = [_run(tmp_path, wait=False) for _ in range(3)]
    results = [_result(p) for p in procs]
    assert all(r["match"] == EXPECTED_MATCH for r in results)
    assert sum(r["misses"] for r in results) >= 1
    assert not [p for p in tmp_path.rglob("*") if ".tmp." in p.name]  # numba writes a temporary, then renames
    after = _run(tmp_path, "--runtime-from-cache")
    assert (after["misses"], after["hits"], after["match"]) == (0, 1, EXPECTED_MATCH)


def _kernel_modules():
    import importlib

    for package in ("lsys", "gmap/kernel", "gmap/organs", "app/desktop/view"):
        for path in sorted((ROOT / package).rglob("_*kernel.py")):  # lsys keeps its kernels in its rooms
            yield importlib.import_module("ramure." + ".".join(path.relative_to(ROOT).with_suffix("").parts))


def test_every_kernel_loads_its_cache_lightly_and_writes_it_in_our_own_folders():
    from ramure.jit import _load_overload

    kernels = 0
    for module in _kernel_modules():
        folder = pathlib.Path(module.__file__).parent
        for name, value in vars(module).items():
            cache = getattr(value, "_cache", None)
            if cache is None or getattr(value, "__module__", None) != module.__name__:
                continue
            kernels += 1
            assert value._cache.load_overload.__func__ is _load_overload, f"{module.__name__}.{name}"
            path = pathlib.Path(cache.cache_path)
            if "NUMBA_CACHE_DIR" in os.environ:
                assert path.is_relative_to(os.environ["NUMBA_CACHE_DIR"])
            else:  # next to the module (its __pycache__), or numba's own per-user folder when that is read-only
                assert path == folder / "__pycache__" or "numba" in path.parts, path
    assert kernels >= 40


def test_no_module_uses_numbas_njit_directly():
    # a kernel decorated with numba.njit would load its cache through numba's whole compiler
    found = []
    for package in ("lsys", "gmap", "metrics", "studies", "app", "ramure"):
        for path in (ROOT / package).rglob("*.py"):
            text = path.read_text(encoding="utf-8")
            if path != ROOT / "ramure" / "jit.py" and ("from numba import" in text or "numba.njit" in text):
                found.append(str(path.relative_to(ROOT)))
    assert found == []


def test_git_ignores_the_cache_files():
    paths = [
        "lsys/interpretation/__pycache__/_turtle_kernel.walk-91.py311.nbi",
        "gmap/organs/__pycache__/_dla_kernel.grow-14.py311.1.nbc",
        "ramure/__pycache__/numba_runtime-0123456789abcdef0123.bin",
    ]
    done = subprocess.run(["git", "-C", str(ROOT), "check-ignore", *paths], capture_output=True, text=True, timeout=60)
    assert done.stdout.split() == paths, done.stderr


def test_a_damaged_cache_file_compiles_anew_instead_of_failing(tmp_path):
    assert _run(tmp_path)["misses"] == 1
    (code,) = [p for p in tmp_path.rglob("*.nbc") if "fill_bracket_pairs" in p.name]
    code.write_bytes(b"\n" + code.read_bytes()[1:])  # the first byte damaged: pickle refuses it
    again = _run(tmp_path)
    assert again["match"] == EXPECTED_MATCH and again["compiled"] == ["fill_bracket_pairs"]
    third = _run(tmp_path)  # and the file written anew loads
    assert (third["misses"], third["hits"]) == (0, 1)


def test_a_damaged_index_is_written_anew(tmp_path):
    assert _run(tmp_path)["misses"] == 1
    (index,) = [p for p in tmp_path.rglob("*.nbi") if "fill_bracket_pairs" in p.name]
    head = index.read_bytes()[:40]
    index.write_bytes(head)  # cut short after numba's version: the rest does not unpickle
    again = _run(tmp_path)
    assert again["match"] == EXPECTED_MATCH and again["compiled"] == ["fill_bracket_pairs"]
    third = _run(tmp_path)
    assert (third["misses"], third["hits"]) == (0, 1)  # the index was written anew
