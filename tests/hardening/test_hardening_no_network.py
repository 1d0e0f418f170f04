"""Ramure never reaches the network on its own (issue 37, the harness): CLI commands and the
explorer model run under an audit hook that records every socket a process opens, connects,
binds or resolves; none may leave the machine (Unix sockets and loopback are local)."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

CHILD = textwrap.dedent("""
    import contextlib, io, json, sys
    seen = []

    def hook(event, args):
        if event in ("socket.connect", "socket.bind", "socket.sendto", "socket.getaddrinfo"):
            seen.append([event, repr(args[1] if event != "socket.getaddrinfo" else args[0])])

    sys.addaudithook(hook)
    from ramure.app.cli import main
    from ramure.app.model import Explorer

    for argv in json.loads(sys.argv[1]):
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            try:
                main(argv)
            except SystemExit:
                pass
    ex = Explorer("grammars/honda_sympodial.lsys", n=5)
    ex.select(ex.session.leaves_with_symbol("F")[-3:])
    ex.regrow(seed=1)
    ex.undo()
    import socket

    socket.getaddrinfo("localhost", 9)  # a local look-up: proves the hook records what it should
    print(json.dumps(seen))
""")

LOCAL = ("127.", "'localhost'", "::1", "'/", "b'\\\\x00")  # loopback, or a Unix socket path


def test_commands_and_the_model_open_no_network_socket(tmp_path):
    argv = [
        ["check", "honda_sympodial"],
        ["derive", "honda_sympodial", "-n", "4", "--json"],
        ["regen", "honda_sympodial", "-n", "5", "--select", "100-120", "--json"],
        ["render", "honda_sympodial", "-n", "4", "--size", "200x200", "-o", str(tmp_path / "p.png")],
        ["export", "honda_sympodial", "-n", "4", "-o", str(tmp_path / "p.glb")],
        ["fruit", "--json"],
    ]
    out = subprocess.run(
        [sys.executable, "-c", CHILD, json.dumps(argv)], capture_output=True, text=True, timeout=300, cwd=tmp_path.parents[0]
    )
    assert out.returncode == 0, out.stderr[-2000:]
    seen = json.loads(out.stdout.strip().splitlines()[-1])
    assert seen[-1] == ["socket.getaddrinfo", "'localhost'"]  # the hook saw the test's own look-up
    remote = [s for s in seen if not any(mark in s[1] for mark in LOCAL)]
    assert remote == [], remote
    assert (tmp_path / "p.png").exists() and (tmp_path / "p.glb").exists()  # the commands did run
