"""The wheel, installed into a fresh virtual environment, works from any directory.

Built from this tree with ``pip wheel``; the fresh environment reuses this environment's
third-party packages (a ``.pth`` line) but not its editable Ramure, so only the wheel's
files can answer ``import ramure``.

The installed copy runs with ``NUMBA_DISABLE_JIT=1``: numba caches compiled kernels next to
their source files, so a fresh install compiles every kernel again (20-60 s on 2 cores) for a
test about packaging. The kernels' compiled behaviour is tested on the editable install.
"""

from __future__ import annotations

import json
import os
import pathlib
import site
import subprocess
import sys
import sysconfig

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCRIPT = """
import ramure, ramure.grammars
from ramure.lsys.regeneration.regen import Session
from ramure.metrics import plant_metrics
assert "honda_sympodial" in ramure.grammars.names()
session = Session(ramure.load("honda_sympodial"), n=6)
before = plant_metrics(session.derivation.skeleton()).branch_count
session.regrow(session.leaves_with_symbol("F")[-5:], seed=3)
after = plant_metrics(session.derivation.skeleton()).branch_count
print(before, after, ramure.__file__)
"""


def _run(args, cwd, **kw):
    return subprocess.run(args, cwd=cwd, capture_output=True, text=True, timeout=300, **kw)


def _run_installed(args, cwd):
    return _run(args, cwd, env={**os.environ, "NUMBA_DISABLE_JIT": "1"})


@pytest.fixture(scope="module")
def fresh(tmp_path_factory):
    work = tmp_path_factory.mktemp("wheel")
    built = _run(
        [sys.executable, "-m", "pip", "wheel", str(ROOT), "--no-deps", "--no-build-isolation", "-q", "-w", str(work / "dist")],
        cwd=work,
    )
    assert built.returncode == 0, built.stderr
    wheel = next((work / "dist").glob("ramure-*.whl"))
    venv = work / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    installed = _run(
        [sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps", "--no-index", "-q", str(wheel)], cwd=work
    )
    assert installed.returncode == 0, installed.stderr
    purelib = _run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], cwd=work)
    ours = sysconfig.get_paths()["purelib"]
    (pathlib.Path(purelib.stdout.strip()) / "ramure_test_deps.pth").write_text("\n".join([ours, *site.getsitepackages()]) + "\n")
    return work, python


def test_wheel_holds_only_ramure(fresh):
    work, _ = fresh
    wheel = next((work / "dist").glob("ramure-*.whl"))
    names = subprocess.run([sys.executable, "-m", "zipfile", "-l", str(wheel)], capture_output=True, text=True, check=True).stdout
    tops = {line.split()[0].split("/")[0] for line in names.splitlines()[1:] if line.strip()}
    assert tops == {"ramure", "ramure-0.1.0.dist-info"}
    assert "ramure/grammars/honda_sympodial.lsys" in names
    for page in ("participant.html", "researcher.html", "study.js", "researcher.js", "study.css"):
        assert f"ramure/studies/webpages/{page}" in names  # what `ramure study serve` serves


def test_wheel_holds_every_package(fresh):
    # a sub-package missing from pyproject's ``packages`` works in the editable install and
    # is silently left out of the wheel
    work, _ = fresh
    wheel = next((work / "dist").glob("ramure-*.whl"))
    names = subprocess.run([sys.executable, "-m", "zipfile", "-l", str(wheel)], capture_output=True, text=True, check=True).stdout
    folders = {"ramure": "ramure", "lsys": "ramure/lsys", "metrics": "ramure/metrics", "gmap": "ramure/gmap"}
    folders |= {"studies": "ramure/studies", "app": "ramure/app", "grammars": "ramure/grammars"}
    expected = {
        f"{installed}/{init.parent.relative_to(ROOT / folder).as_posix()}/__init__.py".replace("/./", "/")
        for folder, installed in folders.items()
        for init in (ROOT / folder).rglob("__init__.py")
    }
    assert "ramure/gmap/kernel/__init__.py" in expected
    assert sorted(e for e in expected if e not in names) == []


def test_script_runs_from_any_directory(fresh, tmp_path):
    _, python = fresh
    out = _run_installed([str(python), "-c", SCRIPT], cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    before, after, where = out.stdout.split()
    assert int(before) > 0 and int(after) > 0
    assert str(ROOT) not in where  # the wheel's copy, not the repository's


def test_no_generic_top_level_modules(fresh, tmp_path):
    _, python = fresh
    for name in ("app", "lsys", "metrics", "gmap", "studies"):
        out = _run([str(python), "-c", f"import {name}"], cwd=tmp_path)
        assert out.returncode != 0 and "ModuleNotFoundError" in out.stderr, name


def test_command_line_derives_a_shipped_grammar(fresh, tmp_path):
    _, python = fresh
    out = _run_installed([str(python.parent / "ramure"), "derive", "honda_sympodial", "--json"], cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    facts = json.loads(out.stdout)
    assert facts["modules"] == 11253 and facts["n"] == 10
