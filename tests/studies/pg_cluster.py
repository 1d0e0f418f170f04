"""A throwaway PostgreSQL server for the tests and the benchmark: Debian's ``postgresql`` package
(installed by ``.ci/sysdeps.sh``, the Makefile's system step), a cluster made by ``initdb`` in a
temporary folder, listening on 127.0.0.1 on a free port and a socket in that folder, and removed
with everything in it by :meth:`Cluster.stop`.

PostgreSQL refuses to run as root: as root the cluster belongs to the ``postgres`` system user
the package creates, and its programs run through ``runuser``.  Authentication is ``trust`` for
the superuser ``ramure``, on this machine only.
"""

from __future__ import annotations

import glob
import os
import pathlib
import shutil
import socket
import subprocess
import tempfile


def postgres_bin() -> pathlib.Path | None:
    """The newest ``/usr/lib/postgresql/N/bin`` holding ``initdb`` and ``pg_ctl``, or None."""
    found = [pathlib.Path(d) for d in glob.glob("/usr/lib/postgresql/*/bin")]
    found = [d for d in found if (d / "initdb").exists() and (d / "pg_ctl").exists()]
    return max(found, key=lambda d: int(d.parent.name) if d.parent.name.isdigit() else 0) if found else None


def why_not() -> str | None:
    """Why no cluster can be started here (None when one can)."""
    if postgres_bin() is None:
        return "PostgreSQL's server programs are absent (no /usr/lib/postgresql/*/bin/initdb): run `make sysdeps` as root"
    if os.geteuid() == 0 and (shutil.which("runuser") is None or _uid("postgres") is None):
        return "running as root without a 'postgres' user and runuser to run the server as"
    return None  # psycopg missing is a failure, not a skip: the `postgres` extra is part of the test install


def _uid(name: str) -> int | None:
    import pwd

    try:
        return pwd.getpwnam(name).pw_uid
    except KeyError:
        return None


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Cluster:
    """One PostgreSQL server in a temporary folder.  ``fsync=False`` (tests) trades durability
    against a power cut, which no test makes, for speed; a killed server process loses nothing
    either way."""

    def __init__(self, fsync: bool = True) -> None:
        self.bin = postgres_bin()
        if self.bin is None:
            raise RuntimeError(why_not())
        self.as_root = os.geteuid() == 0
        # As root the server's user must reach the folder: /tmp, not a TMPDIR under /root.
        self.root = pathlib.Path(tempfile.mkdtemp(prefix="ramure-pg-", dir="/tmp" if self.as_root else None))
        self.data = self.root / "data"
        self.port = _free_port()
        self.fsync = fsync
        self._count = 0

    def _run(self, *argv: str) -> subprocess.CompletedProcess:
        command = [str(self.bin / argv[0]), *argv[1:]]
        if self.as_root:
            command = ["runuser", "-u", "postgres", "--", *command]
        return subprocess.run(command, cwd=self.root, capture_output=True, text=True, timeout=120, check=True)

    def start(self) -> Cluster:
        if self.as_root:
            os.chown(self.root, _uid("postgres"), -1)  # type: ignore[arg-type]
        self._run("initdb", "-D", str(self.data), "-A", "trust", "-U", "ramure", "--no-locale", "-E", "UTF8", "--no-sync")
        options = (
            f"-p {self.port} -c listen_addresses=127.0.0.1 -c unix_socket_directories={self.root} "
            f"-c fsync={'on' if self.fsync else 'off'} -c max_connections=300"
        )
        self._run("pg_ctl", "-D", str(self.data), "-o", options, "-l", str(self.root / "server.log"), "-w", "-t", "60", "start")
        return self

    def url(self, dbname: str = "postgres") -> str:
        return f"postgresql://ramure@127.0.0.1:{self.port}/{dbname}"

    def new_database(self, prefix: str = "study") -> str:
        """A new empty database on the server; its URL."""
        import psycopg

        self._count += 1
        name = f"{prefix}_{self._count}"
        with psycopg.connect(self.url(), autocommit=True) as conn:
            conn.execute(f'CREATE DATABASE "{name}"')
        return self.url(name)

    def stop(self) -> None:
        """Stop the server at once and delete its folder."""
        try:
            if (self.data / "postmaster.pid").exists():
                self._run("pg_ctl", "-D", str(self.data), "-m", "immediate", "-w", "stop")
        finally:
            shutil.rmtree(self.root, ignore_errors=True)

    def __enter__(self) -> Cluster:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()
