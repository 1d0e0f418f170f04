"""Every ``ramure`` command with bad input: exit 2, one clear line naming the problem, no traceback.

Cases run in groups: one child process per group calls ``app.cli.main`` for each case
(``python -m ramure.app.cli`` startup is most of the cost), and a few run as the real command.
"""

from __future__ import annotations

import json
import pathlib
import subprocess
import sys
import textwrap

import pytest

ROOT = pathlib.Path(__file__).parents[2]
G = "grammars/honda_sympodial.lsys"

_CHILD = textwrap.dedent("""
    import contextlib, io, json, sys, traceback
    from ramure.app.cli import main
    out = []
    for argv in json.loads(sys.argv[1]):
        err = io.StringIO()
        try:
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                rc = main(argv)
        except SystemExit as exc:
            rc = exc.code
        except BaseException:
            rc, err = "traceback", io.StringIO(traceback.format_exc())
        out.append({"rc": rc, "stderr": err.getvalue()})
    print(json.dumps(out))
""")


@pytest.fixture(scope="module")
def places(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cli")
    (tmp / "empty.lsys").write_text("")
    (tmp / "adir").mkdir()
    (tmp / "div.lsys").write_text("n: 2\nw: A(1)\np:\n  A(x) -> A(x/0)\n")
    (tmp / "notdb.db").write_text("garbage, not sqlite")
    (tmp / "afile").write_text("x")
    (tmp / "binary.lsys").write_bytes(bytes(range(256)))
    return tmp


def _cases(t):
    """(argv, words the one-line message must contain)."""
    return [
        (["check", "/nonexistent.lsys"], "No such file"),
        (["check", f"{t}/adir"], "Is a directory"),
        (["check", f"{t}/empty.lsys"], "no axiom"),
        (["derive", f"{t}/div.lsys"], "division by zero"),
        (["derive", f"{t}/binary.lsys"], "not UTF-8"),
        (["derive", G, "-n", "-1"], "-n must be >= 0"),
        (["derive", G, "-n", "50"], "limit"),
        (["derive", "grammars/algae.lsys", "-n", "100000000"], "limit"),
        (["derive", G, "--set", "r1"], "NAME=VALUE"),
        (["derive", G, "--set", "zz=1"], "no constant 'zz'"),
        (["derive", G, "--set", "r1=abc"], "not a number"),
        (["derive", G, "--set", "r1=nan", "--json"], "not a finite number"),
        (["derive", G, "--set", "a1=inf", "--json"], "not a finite number"),
        (["derive", G, "-n", "2", "--seed", "-1"], "seed"),
        (["render", G, "-n", "2", "-o", f"{t}/adir"], "is a directory"),
        (["render", G, "-n", "2", "-o", f"{t}/missing/sub/../x.txt"], ".png"),
        (["render", G, "-n", "2", "-o", f"{t}/x.png", "--size", "0x0"], "1..10000"),
        (["render", G, "-n", "2", "-o", f"{t}/x.png", "--size", "axb"], "WIDTHxHEIGHT"),
        (["render", G, "-n", "2", "-o", "/proc/nope/x.png"], "No such file"),
        (["leaves", G, "-n", "-1"], "must be >= 0"),
        (["regen", G, "-n", "3", "--select", "abc"], "is not a leaf id or a range"),
        (["regen", G, "-n", "3", "--select", "99999"], "99999 is not a leaf of the current plant"),
        (["regen", G, "-n", "3", "--select", "0"], "not a leaf"),
        (["regen", G, "-n", "3", "--select", "10-5"], "goes backwards: write 5-10"),
        (["regen", G, "-n", "3", "--select", "0-99999999999"], "more than"),
        (["regen", G, "-n", "3", "--select", ","], "at least one leaf"),
        (["regen", G, "-n", "3", "--select", "70", "--rho", "0"], "rho"),
        (["regen", G, "-n", "3", "--select", "70", "--rho", "nan"], "rho"),
        (["regen", G, "-n", "3", "--select", "70", "--min-ascend", "-3"], "--min-ascend"),
        (["regen", G, "-n", "3", "--select", "70", "--regen-seed", "-4"], "seed"),
        (["regen", G, "-n", "3", "--select", "70", "-o", f"{t}/adir"], "is a directory"),
        (["regen", G, "-n", "3", "--select", "70", "-o", "/proc/nope/s.json"], "cannot save"),
        (["metrics", G, "-n", "3", "--select", "99999"], "not leaf id"),
        (["metrics", G, "-n", "3", "--segments", "999"], "out of range"),
        (["metrics", G, "-n", "3", "--segments", "5-1"], "goes backwards: write 1-5"),
        (["explore", G, "-n", "2", "-o", f"{t}/afile", "--no-thumbnails", "--no-cache"], "not a directory"),
        (["explore", G, "-n", "2", "-o", f"{t}/e", "--beta", "nan", "--no-cache"], "beta"),
        (["explore", G, "-n", "2", "-o", f"{t}/e", "--thumb-size", "0", "--no-cache"], "--thumb-size"),
        (["explore", G, "-n", "2", "-o", f"{t}/e", "--constants", "zz", "--no-cache"], "unknown constant"),
        (["qualify", G, "-n", "2", "--qualifier", "zzz", "--no-cache"], "unknown qualifier"),
        (["qualify", G, "-n", "2", "--qualifier", "dense", "--rho", "0", "--no-cache"], "rho"),
        (["qualify", G, "-n", "2", "--qualifier", "dense", "--tries", "0", "--no-cache"], "--tries"),
        (["qualify", G, "-n", "2", "--qualifier", "dense", "--trim", "nan", "--no-cache"], "--trim"),
        (["fruit", "--set", "zz=1"], "unknown fruit parameter"),
        (["fruit", "--set", "precision=nan"], "precision"),
        (["fruit", "--subdivide", "volume:9"], "0..4"),
        (["fruit", "--set", "precision=2000", "--subdivide", "volume:2"], "limit of 8,000,000"),
        (["fruit", "--set", "precision=2000", "--set", "ph=2000"], "limit of 8,000,000"),
        (["fruit", "--cut", "z=abc"], "number"),
        (["fruit", "--cut", "z=nan"], "finite"),
        (["fruit", "--cut", "q=0"], "x=VALUE"),
        (["fruit", "--size", "0x0", "-o", f"{t}/f.png"], "1..10000"),
        (["fruit", "-o", f"{t}/adir"], ".png picture or a .vtu"),
        (["fruit", "-o", "/proc/f.vtu"], "/proc/f.vtu"),
        (["study", "status", f"{t}/notdb.db"], "not a Ramure study"),
        (["study", "analyze", f"{t}/notdb.db", "-o", f"{t}/rep"], "not a Ramure study"),
        (["study", "export-csv", f"{t}/notdb.db", "-o", f"{t}/csv"], "not a Ramure study"),
        (["study", "status", "/nonexistent.db"], "no such study"),
        (["study", "simulate", "--participants", "0", "--grammars", "1"], "--participants"),
        (["study", "simulate", "--participants", "2", "--grammars", "0"], "--grammars"),
        (["study", "simulate", "--participants", "2", "--grammars", "1", "--noise", "-1"], "--noise"),
    ]


def _groups():
    return [(i, i + 16) for i in range(0, 64, 16)]  # 61 cases in 4 child processes


@pytest.mark.parametrize("lo, hi", _groups())
def test_bad_input_exits_2_with_one_clear_line(places, lo, hi):
    cases = _cases(places)[lo:hi]
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD, json.dumps([argv for argv, _ in cases])],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    failures = []
    for (argv, words), got in zip(cases, json.loads(proc.stdout.splitlines()[-1])):
        err = got["stderr"].strip()
        lines = [line for line in err.splitlines() if line.strip()]
        ok = got["rc"] == 2 and "Traceback" not in err and words in err and lines
        # argparse prints usage lines; our own messages are one line (plus a caret for grammar errors)
        if ok and not lines[-1].startswith(("ramure", "usage")) and not err.startswith("ramure"):
            ok = False
        if not ok:
            failures.append(f"{' '.join(argv)} -> rc={got['rc']}: {err[-400:]}")
    assert not failures, "\n".join(failures)


def test_nothing_is_left_behind_by_refused_outputs(places):
    assert not list(places.glob("*.tmp")) and not (places / "adir.png").exists()
    assert list((places / "adir").iterdir()) == []


@pytest.mark.parametrize(
    "argv, words",
    [
        (["derive", G, "--set", "r1=nan"], "not a finite number"),
        (["regen", G, "-n", "3", "--select", "10-5"], "goes backwards: write 5-10"),
    ],
)
def test_real_command_prints_one_line_and_exits_2(argv, words):
    proc = subprocess.run([sys.executable, "-m", "ramure.app.cli", *argv], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and words in proc.stderr and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and proc.stdout == ""
