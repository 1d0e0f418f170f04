"""Files Ramure writes survive crashes, kill -9 and full disks (issue 11, "Files and databases")."""

import errno
import os
import pathlib
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import ramure.io as atomic
from ramure.errors import RamureError

GRAMMAR = pathlib.Path(__file__).resolve().parents[2] / "grammars" / "ternary_branching.lsys"


def no_space(*_args, **_kwargs):
    raise OSError(errno.ENOSPC, "No space left on device")


def test_write_text_replaces_whole_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "g.lsys"
    target.write_text("old")
    atomic.write_text(target, "new text")
    assert target.read_text() == "new text"
    assert [p.name for p in tmp_path.iterdir()] == ["g.lsys"]


@pytest.mark.parametrize("how", ["write_text", "save_mesh", "write_with"])
def test_full_disk_is_a_clear_error_and_keeps_the_previous_file(tmp_path, monkeypatch, how):
    import pyvista as pv

    target = tmp_path / ("m.vtu" if how == "save_mesh" else "g.txt")
    target.write_bytes(b"previous")
    monkeypatch.setattr(os, "fsync", no_space)
    with pytest.raises(RamureError, match="No space left on device"):
        if how == "write_text":
            atomic.write_text(target, "x" * 100000)
        elif how == "save_mesh":
            atomic.save_mesh(pv.Sphere().cast_to_unstructured_grid(), target)
        else:
            atomic.write_with(target, lambda tmp: pathlib.Path(tmp).write_text("y"))
    assert target.read_bytes() == b"previous"
    assert sorted(p.name for p in tmp_path.iterdir()) == [target.name]


def test_a_failing_writer_keeps_the_previous_file(tmp_path):
    target = tmp_path / "a.png"
    target.write_bytes(b"png")

    def broken(tmp):
        pathlib.Path(tmp).write_bytes(b"half")
        raise RuntimeError("renderer died")

    with pytest.raises(RuntimeError):
        atomic.write_with(target, broken)
    assert target.read_bytes() == b"png" and len(list(tmp_path.iterdir())) == 1


def test_save_mesh_vtu_reads_back(tmp_path):
    import pyvista as pv

    grid = pv.Sphere().cast_to_unstructured_grid()
    path = atomic.save_mesh(grid, tmp_path / "s.vtu")
    back = pv.read(path)
    assert back.n_points == grid.n_points and np.allclose(back.points, grid.points)


def test_explorer_save_grammar_full_disk_keeps_the_original(tmp_path, monkeypatch):
    from ramure.app.model import Explorer

    target = tmp_path / "plant.lsys"
    target.write_text(GRAMMAR.read_text())
    ex = Explorer(target)
    ex.text = ex.text + "\n/* edited */\n"
    monkeypatch.setattr(os, "fsync", no_space)
    with pytest.raises(RamureError, match="No space"):
        ex.save_grammar(target)
    assert target.read_text() == GRAMMAR.read_text()


def test_session_save_goes_through_the_atomic_writer(tmp_path, monkeypatch):
    from ramure.lsys import LSystem
    from ramure.lsys.regeneration.regen import Session

    path = tmp_path / "s.json"
    path.write_text("{}")
    monkeypatch.setattr(os, "fsync", no_space)
    with pytest.raises(RamureError, match="No space"):
        Session(LSystem.from_file(GRAMMAR), n=2).save(path)
    assert path.read_text() == "{}"


def run_cli(*args, **kw):
    return subprocess.run([sys.executable, "-m", "ramure.app.cli", *args], capture_output=True, text=True, timeout=300, **kw)


@pytest.mark.parametrize("setting", ["rotx=nan", "longueur=inf", "rotz=1e308", "rotx=-inf"])
def test_fruit_refuses_non_finite_settings(setting, tmp_path):
    out = run_cli("fruit", "--set", setting, "-o", str(tmp_path / "f.vtu"), "--json")
    assert out.returncode == 2 and "finite" in out.stderr and "Traceback" not in out.stderr
    assert not (tmp_path / "f.vtu").exists()


SPAWNER = r"""
import os, sys, pathlib
from ramure.app.model import Explorer
target, kind, text = sys.argv[1], sys.argv[2], sys.argv[3]
ex = Explorer(pathlib.Path(text))  # imports and the first turtle call paid once, not per kill


def save_forever():
    i = 0
    while True:
        i += 1
        if kind == "grammar":
            ex.text = pathlib.Path(text).read_text() + "/* " + "x" * (200000 + i % 7) + " */\n"
            ex.save_grammar(target)
        else:
            ex.export(target)


for line in sys.stdin:  # "go": fork a saver and print its pid; "reap PID": wait for it
    if line.startswith("go"):
        pid = os.fork()
        if pid == 0:
            save_forever()
        print(pid, flush=True)
    else:
        os.waitpid(int(line.split()[1]), 0)
        print("reaped", flush=True)
"""


@pytest.mark.parametrize("kind,suffix", [("grammar", ".lsys"), ("export", ".vtp")])
def test_kill_9_during_saves_leaves_a_whole_file(tmp_path, kind, suffix):
    """50 kill -9 at random moments of a save loop: the file is always a complete version.

    Each saver is a fork of one process that has loaded Ramure (a fresh interpreter per kill
    spent about 2 s importing and loading compiled kernels before its first save).
    """
    target = tmp_path / f"plant{suffix}"
    grammar = tmp_path / "g.lsys"
    grammar.write_text(GRAMMAR.read_text().replace("n: 6", "n: 3"))
    if kind == "grammar":
        target.write_text(grammar.read_text())
    else:
        from ramure.app.model import Explorer

        Explorer(grammar).export(target)
    rng = np.random.default_rng(7)
    spawner = subprocess.Popen(
        [sys.executable, "-c", SPAWNER, str(target), kind, str(grammar)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    try:
        for _ in range(50):
            spawner.stdin.write("go\n")
            spawner.stdin.flush()
            pid = int(spawner.stdout.readline())
            time.sleep(float(rng.uniform(0.0, 0.25)))
            os.kill(pid, signal.SIGKILL)
            spawner.stdin.write(f"reap {pid}\n")
            spawner.stdin.flush()
            assert spawner.stdout.readline().strip() == "reaped"
            if kind == "grammar":
                text = target.read_text()
                assert text == grammar.read_text() or (
                    text.endswith(" */\n") and text.startswith(grammar.read_text()) and len(text) > 200000
                )
            else:
                import pyvista as pv

                assert pv.read(target).n_points > 0
    finally:
        spawner.kill()
        spawner.wait()


def test_closed_pipe_is_a_quiet_exit():
    """`ramure leaves ... | head -1`: no "Broken pipe", exit 0."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "ramure.app.cli", "leaves", "honda_sympodial", "-n", "12"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    proc.stdout.readline()
    proc.stdout.close()  # what head does after its first line
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 0 and "Broken pipe" not in err and "Traceback" not in err


def test_study_report_full_disk_keeps_previous_files(tmp_path, monkeypatch):
    """Reports go through the atomic writer too: a failing write leaves the old summary whole."""
    from ramure.studies import report

    out = tmp_path / "report"
    out.mkdir()
    (out / "summary.json").write_text('{"old": true}')
    monkeypatch.setattr(os, "fsync", no_space)
    with pytest.raises(RamureError, match="No space"):
        report.write_text(out / "summary.json", "{}")
    assert (out / "summary.json").read_text() == '{"old": true}'
    assert report.write_with is atomic.write_with and report.open_atomic is atomic.open_atomic


def test_the_next_write_removes_what_a_killed_writer_left(tmp_path):
    """Issue 37, item 9: a writer killed mid-write leaves its temporary file; the next write of
    the same file removes it, and leaves a live writer's temporary file alone."""
    target = tmp_path / "big.bin"
    child = textwrap.dedent(f"""
        import time, ramure.io as atomic
        def slow(tmp):
            open(tmp, "wb").write(b"x" * 1_000_000)
            print("written", flush=True)
            time.sleep(60)
        atomic.write_with({str(target)!r}, slow)
    """)
    proc = subprocess.Popen([sys.executable, "-c", child], stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "written"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    left = list(tmp_path.glob(".big.bin.*"))
    assert len(left) == 1 and left[0].stat().st_size == 1_000_000 and f".{proc.pid}." in left[0].name
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        live = tmp_path / f".big.bin.{sleeper.pid}.abcd1234.tmp"
        live.write_bytes(b"a write still running")
        atomic.write_bytes(target, b"new")
        assert target.read_bytes() == b"new"
        assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["big.bin", live.name])
    finally:
        sleeper.kill()
        sleeper.wait()
