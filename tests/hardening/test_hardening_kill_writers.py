"""Kill -9 of the writers issue 37 names (item "the harness"): the glTF exports (.glb, .gltf),
PNG renders and the study report folder.  A writer is killed at random moments of a write loop;
after each kill every file is a whole one (the reference, or for pictures a whole PNG of the
reference's size); then one more write leaves no temporary file behind."""

from __future__ import annotations

import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

GRAMMAR = pathlib.Path(__file__).resolve().parents[2] / "grammars" / "ternary_branching.lsys"

SPAWNER = r"""
import os, sys, time, pathlib
kind, target = sys.argv[1], pathlib.Path(sys.argv[2])
if kind == "report":
    from ramure.studies.report import write_report
    from ramure.studies.simulate import simulate_study

    data = simulate_study(participants=3, grammars=2, seed=1)
    write = lambda: write_report(data, target)
else:
    from ramure.app.model import Explorer

    ex = Explorer(pathlib.Path(sys.argv[3]), n=3)
    if kind == "png":
        from ramure.app.render import render_plant

        skeleton = ex.skeleton
        write = lambda: render_plant(skeleton, target, size=(400, 400))
    else:
        mesh = ex.mesh
        write = lambda: ex.export(target)

# Writers are forks of this process, which has loaded Ramure once (and never opens a render
# window itself).  "go": fork a writer that writes for ever, print its pid; "reap PID": wait
# for it; "once": fork a writer that writes once, wait for it, print its exit status.
for line in sys.stdin:
    pid = os.fork() if line.startswith(("go", "once")) else int(line.split()[1])
    if pid == 0:
        while True:
            write()
            if line.startswith("once"):
                os._exit(0)
    if line.startswith("go"):
        print(pid, flush=True)
    else:
        print(os.waitpid(pid, 0)[1], flush=True)
"""


def temporaries(folder: pathlib.Path) -> list[str]:
    return sorted(p.name for p in folder.rglob(".*.tmp*"))


def wait_for_a_write(folder: pathlib.Path, timeout: float = 120.0) -> None:
    """Return once a temporary file shows in ``folder``: the writer has started writing."""
    end = time.monotonic() + timeout
    while not temporaries(folder) and time.monotonic() < end:
        time.sleep(0.005)


def whole_png(path: pathlib.Path, size=(400, 400)) -> None:
    from PIL import Image

    with Image.open(path) as image:
        image.load()  # a truncated PNG raises here
        assert image.size == size


def whole_report(folder: pathlib.Path, names: list[str]) -> None:
    import csv

    assert sorted(p.name for p in folder.iterdir() if not p.name.startswith(".")) == names
    for name in names:
        path = folder / name
        if name.endswith(".png"):
            from PIL import Image

            with Image.open(path) as image:
                image.load()
        elif name.endswith(".json"):
            json.loads(path.read_text())
        elif name.endswith(".html"):
            assert path.read_text().rstrip().endswith("</html>")
        else:
            assert list(csv.reader(path.open(newline="", encoding="utf-8")))


@pytest.mark.parametrize("kind, name", [("glb", "plant.glb"), ("gltf", "plant.gltf"), ("png", "plant.png"), ("report", "report")])
def test_kill_9_during_writes_leaves_whole_files_and_no_debris_after_the_next(tmp_path, kind, name):
    target = tmp_path / name
    spawner = subprocess.Popen(
        [sys.executable, "-c", SPAWNER, kind, str(target), str(GRAMMAR)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )

    def ask(line: str) -> str:
        spawner.stdin.write(line + "\n")
        spawner.stdin.flush()
        return spawner.stdout.readline().strip()

    rng = np.random.default_rng(37)
    left = 0
    try:
        assert ask("once") == "0"
        t0 = time.perf_counter()
        assert ask("once") == "0"
        seconds = min(time.perf_counter() - t0, 2.0)  # how long a writer lives before its kill
        check = whole_files(kind, target)
        for _ in range(5 if kind == "report" else 15):  # a report takes seconds to write
            pid = int(ask("go"))
            wait_for_a_write(tmp_path)  # a fresh fork's first render can take seconds on a busy machine
            time.sleep(float(rng.uniform(0.0, seconds)))
            os.kill(pid, signal.SIGKILL)
            assert ask(f"reap {pid}") == str(int(signal.SIGKILL))
            check()
            left += bool(temporaries(tmp_path))
        assert left, "no kill landed during a write: the test did not test anything"
        assert ask("once") == "0"
        check()
        assert temporaries(tmp_path) == []
    finally:
        spawner.kill()
        spawner.wait()


def whole_files(kind: str, target: pathlib.Path):
    """A check that the files a finished write left are still whole (for a report, the same
    names, each file readable to its end; for an export, the very same bytes)."""
    if kind == "report":
        names = sorted(p.name for p in target.iterdir())
        assert "summary.json" in names and "dendrogram.png" in names
        return lambda: whole_report(target, names)
    if kind == "png":
        return lambda: whole_png(target)
    reference = target.read_bytes()
    return lambda: target.read_bytes() == reference or pytest.fail("the export is not the whole file")
