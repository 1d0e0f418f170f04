"""``ramure study serve`` under load: 200 simulated participants answering at once.

The server runs as a researcher starts it (``ramure study serve``, its own process, durable
commits) on 127.0.0.1; the participants are asyncio tasks sharing one httpx client.  Each joins,
sorts the 27 pictures into four groups, chooses representatives, rates and names every group and
finishes: 16 answers, each acknowledged only once committed.  Reported: answers per second, the
median and 95th-percentile latency of an answer, and answers lost: acknowledged answers that
the database does not hold afterwards (must be 0).  ``kill`` does the same while the server is
killed with SIGKILL once, a third of the way in, and restarted; participants whose request was
cut short read their state again and carry on, as the page does after a reload.
Targets: nothing lost, every test finished, and at most 10 ms of the server's CPU per answer
(the latencies are reported, not judged: on a shared machine they measure the neighbours too);
bounded at 180 s of answering.

Each runs on a SQLite file and on PostgreSQL (``_postgresql``): a throwaway cluster from Debian's
package (``tests/studies/pg_cluster.py``, fsync on), the study created from its URL and served
from it.  ``tests/studies/test_study_load.py`` runs the same crowd, smaller, in ``make test``.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import pathlib
import signal
import socket
import sqlite3
import subprocess
import sys
import tempfile
import time
import urllib.request

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "studies"))  # pg_cluster: a throwaway PostgreSQL server

PARTICIPANTS = int(os.environ.get("RAMURE_BENCH_PARTICIPANTS", "200"))
#: The server's own CPU time per answer (HTTP, checks, SQL): judged instead of the latency, which on a
#: shared 2-core machine measures the other processes as much as the server.
TARGET_SERVER_CPU_MS = 10.0
BOUND_SECONDS = 180.0
SIZES = (9, 9, 8, 1)
NOT_ANSWERS = ("start", "resume", "consent", "external_id")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Server:
    """``ramure study serve DB`` in a child process."""

    def __init__(self, db: pathlib.Path | str, port: int) -> None:
        self.db, self.port = db, port
        self.base = f"http://127.0.0.1:{port}"
        self.process: subprocess.Popen | None = None

    def start(self) -> None:
        argv = [sys.executable, "-m", "ramure.app.cli", "study", "serve", str(self.db), "--port", str(self.port)]
        self.process = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 60
        while True:
            try:
                urllib.request.urlopen(self.base + "/api/study", timeout=2).read()
                return
            except OSError:
                if time.monotonic() > deadline or self.process.poll() is not None:
                    raise RuntimeError("ramure study serve did not start") from None
                time.sleep(0.05)

    def cpu_seconds(self) -> float:
        """CPU time the server process has used so far (Linux /proc), 0 elsewhere."""
        try:
            fields = pathlib.Path(f"/proc/{self.process.pid}/stat").read_text().rsplit(")", 1)[1].split()
        except (OSError, AttributeError):
            return 0.0
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    def stop(self, sig: int = signal.SIGTERM) -> None:
        if self.process is not None:
            self.cpu_used = getattr(self, "cpu_used", 0.0) + self.cpu_seconds()
            self.process.send_signal(sig)
            self.process.wait(timeout=60)
            self.process = None


class Participant:
    """One simulated participant: a fixed plan of answers, sent one at a time."""

    def __init__(self, client, stats: dict) -> None:
        self.client, self.stats = client, stats
        self.acked = 0
        self.code = ""

    async def _request(self, method: str, url: str, **kwargs):
        """A request retried (the state re-read by the caller) while the server is away."""
        import httpx

        while True:
            try:
                return await self.client.request(method, url, **kwargs)
            except httpx.TransportError:
                self.stats["retries"] += 1
                await asyncio.sleep(0.2)

    async def state(self) -> dict:
        r = await self._request("GET", f"/api/p/{self.code}/state", headers=self.headers)
        r.raise_for_status()
        return r.json()

    async def run(self) -> None:
        r = await self._request("POST", "/api/join", json={"consent": True})
        r.raise_for_status()
        self.code, token = r.json()["code"], r.json()["token"]
        self.headers = {"Authorization": f"Bearer {token}"}
        state = await self._pages(await self.state())  # the instructions and practice pages first
        shown, groups, start = state["pictures"], [], 0
        for size in SIZES:
            groups.append(shown[start : start + size])
            start += size
        plan: list[dict] = [dict(action="groups", groups=groups)]
        for label, pics in enumerate(groups, start=1):
            if len(pics) > 1:
                plan += [dict(action="representative", group=label, picture=pics[-1])]
                plan += [dict(action="rate", group=label, representative_quality=1 + label % 4)]
            plan += [dict(action="rate", group=label, usefulness=1 + label % 4, difference=4 - label % 4)]
            plan += [dict(action="add_word", group=label, text=f"word {label}")]
        plan.append(dict(action="finish"))
        base = state["version"]  # answers given before the plan: the pages before the set
        while state["version"] - base < len(plan):
            body = {**plan[state["version"] - base], "version": state["version"], "part": state["part"]}
            state = await self._send(state, body)
        await self._pages(state)  # the attention and demographics questions after the set

    async def _pages(self, state: dict) -> dict:
        """Answer the study's pages of text and questions until a picture set or the end (the
        questions with their first option)."""
        while "page" in state:
            page = state["page"]
            answers = {q["key"]: q["options"][0] for q in page["questions"]}
            body = {"page": page["kind"], "version": state["version"], **({"answers": answers} if answers else {})}
            state = await self._send(state, body)
        return state

    async def _send(self, state: dict, body: dict) -> dict:
        """Post one answer; on a refusal or a lost connection, the state read again (the page's way)."""
        t0 = time.perf_counter()
        try:
            r = await self.client.post(f"/api/p/{self.code}/answer", json=body, headers=self.headers)
        except Exception:  # the server went away mid-answer: read what it kept, carry on
            self.stats["retries"] += 1
            await asyncio.sleep(0.2)
            return await self.state()
        if r.status_code != 200:
            self.stats["refused"] += 1
            return await self.state()
        self.stats["latencies"].append(time.perf_counter() - t0)
        self.acked += 1
        return r.json()


def _png() -> bytes:
    """A tiny valid PNG (serve refuses a study whose picks have no picture)."""
    import struct
    import zlib

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    rows = b"".join(b"\x00" + b"\x40\x90\x30" * 4 for _ in range(4))
    header = chunk(b"IHDR", struct.pack(">IIBBBBB", 4, 4, 8, 2, 0, 0, 0))
    return b"\x89PNG\r\n\x1a\n" + header + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b"")


def _reader(db: pathlib.Path | str):
    """A connection of the database's own driver (not Ramure's), to count what it holds."""
    if isinstance(db, str):
        import psycopg

        return psycopg.connect(db, autocommit=True)
    return sqlite3.connect(f"file:{db}?mode=ro", uri=True)


def _stored_answers(db: pathlib.Path | str) -> dict[str, int]:
    conn = _reader(db)
    try:
        marks = ", ".join(["%s" if isinstance(db, str) else "?"] * len(NOT_ANSWERS))
        rows = conn.execute(
            "SELECT p.code, count(e.id) FROM participants p LEFT JOIN events e ON e.participant_id = p.id "
            f"AND e.action NOT IN ({marks}) GROUP BY p.id",
            NOT_ANSWERS,
        ).fetchall()
        if not isinstance(db, str):
            assert conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        return dict(rows)
    finally:
        conn.close()


def _finished(db: pathlib.Path | str) -> int:
    conn = _reader(db)
    try:
        return conn.execute("SELECT count(*) FROM tests WHERE finished_at IS NOT NULL").fetchone()[0]
    finally:
        conn.close()


async def _crowd(server: Server, kill_after: int | None, participants: int) -> tuple[list[Participant], dict, float]:
    import httpx

    stats: dict = dict(latencies=[], refused=0, retries=0, kills=0)
    async with contextlib.AsyncExitStack() as stack:  # a client each: one connection, as one browser tab
        clients = [
            await stack.enter_async_context(httpx.AsyncClient(base_url=server.base, timeout=60.0)) for _ in range(participants)
        ]
        people = [Participant(client, stats) for client in clients]

        async def killer():
            while len(stats["latencies"]) < (kill_after or 0):
                await asyncio.sleep(0.01)
            server.stop(signal.SIGKILL)
            stats["kills"] += 1
            stats["acked_at_kill"] = len(stats["latencies"])
            await asyncio.to_thread(server.start)

        t0, cpu0 = time.perf_counter(), time.process_time()
        tasks = [asyncio.create_task(p.run()) for p in people]
        if kill_after:
            tasks.append(asyncio.create_task(killer()))
        done, late = await asyncio.wait(tasks, timeout=BOUND_SECONDS)
        for task in late:  # past the bound: report what was done, judged not ok
            task.cancel()
        stats["timed_out"] = len(late)
        for task in done:
            task.result()  # a participant's own failure (not a refused answer) is the benchmark's
        stats["client_cpu"] = time.process_time() - cpu0
        return people, stats, time.perf_counter() - t0


def load(kill: bool = False, backend: str = "sqlite", participants: int = PARTICIPANTS) -> dict:
    """``participants`` answering at once against ``ramure study serve`` on 127.0.0.1, the study on
    ``backend`` (``sqlite`` or ``postgresql``); ``kill``: the server is killed -9 and restarted a
    third of the way in.  Returns the figures (see the module docstring)."""
    with tempfile.TemporaryDirectory(prefix="ramure-bench-web-") as tmp, contextlib.ExitStack() as stack:
        db: pathlib.Path | str = pathlib.Path(tmp) / "study.db"
        if backend == "postgresql":
            from pg_cluster import Cluster

            db = stack.enter_context(Cluster(fsync=True)).new_database("load")
        elif backend != "sqlite":
            raise ValueError(f"backend {backend!r} is not sqlite or postgresql")
        return _load_on(db, pathlib.Path(tmp), kill, participants) | dict(backend=backend)


def _load_on(db: pathlib.Path | str, folder: pathlib.Path, kill: bool, participants: int) -> dict:
    import numpy as np

    from ramure.studies.picks import lattice_picks
    from ramure.studies.storage import Study

    picture = folder / "plant.png"
    picture.write_bytes(_png())
    picks = [
        dict(id=p.id, variant=p.variant, pca=list(p.pca), params=p.params, image=str(picture)) for p in lattice_picks(seed=1)
    ]
    Study.create(db, grammars={"plants": picks}, name="load", folder=folder).close()
    server = Server(db, _free_port())
    server.start()
    try:
        per_participant = 1 + 3 * 4 + 2 + 1
        people, stats, seconds = asyncio.run(_crowd(server, participants * per_participant // 3 if kill else None, participants))
    finally:
        server.stop()
    stored = _stored_answers(db)
    lost = sum(max(0, p.acked - stored.get(p.code, 0)) for p in people)
    finished = _finished(db)
    lat = np.array(stats["latencies"])
    p95 = float(np.percentile(lat, 95))
    out = dict(
        seconds=round(seconds, 2),
        participants=participants,
        answers=int(lat.size),
        answers_per_second=round(lat.size / seconds, 1),
        p50_latency_ms=round(1000 * float(np.median(lat)), 1),
        p95_latency_ms=round(1000 * p95, 1),
        answers_lost=lost,
        tests_finished=finished,
        server_cpu_ms_per_answer=round(1000 * server.cpu_used / max(1, lat.size), 2),
        client_cpu_seconds=round(stats["client_cpu"], 1),
        load_average=round(os.getloadavg()[0], 1),
        refused=stats["refused"],
        retries=stats["retries"],
        target_server_cpu_ms=TARGET_SERVER_CPU_MS,
        unfinished_at_bound=stats["timed_out"],
        ok=lost == 0 and finished == participants and server.cpu_used / max(1, lat.size) * 1000 <= TARGET_SERVER_CPU_MS,
    )
    if kill:
        out.update(kills=stats["kills"], acked_before_kill=stats.get("acked_at_kill"))
    return out


def bench_serve_200_participants():
    """200 participants answer at once on SQLite; nothing acknowledged may be lost."""
    return load(kill=False)


def bench_serve_200_participants_kill():
    """The same crowd with the server killed (SIGKILL) and restarted a third of the way in."""
    return load(kill=True)


def bench_serve_200_participants_postgresql():
    """200 participants answer at once, the study on PostgreSQL; nothing acknowledged may be lost."""
    return load(kill=False, backend="postgresql")


def bench_serve_200_participants_kill_postgresql():
    """The PostgreSQL crowd with Ramure's server killed (SIGKILL) and restarted a third of the way in."""
    return load(kill=True, backend="postgresql")


if __name__ == "__main__":
    names = [n for n in globals() if n.startswith("bench_")]
    for name in names if len(sys.argv) < 2 else sys.argv[1:]:
        print(json.dumps({"benchmark": f"bench_web_study.{name[6:]}", **globals()[name]()}), flush=True)
