"""Helpers for the web study tests: a study with pictures on disk, and a participant that
answers everything over HTTP (any client with httpx's ``get``/``post``)."""

from __future__ import annotations

import pathlib
import sqlite3

from ramure.studies.picks import lattice_picks
from ramure.studies.storage import Study


def png(path: pathlib.Path, shade: int) -> None:
    """A tiny valid PNG of one grey ``shade`` (so the browser shows a picture, not a broken icon)."""
    import struct
    import zlib

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    rows = b"".join(b"\x00" + bytes([shade, 255 - shade, 90]) * 8 for _ in range(8))
    header = struct.pack(">IIBBBBB", 8, 8, 8, 2, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def make_study(
    folder: pathlib.Path,
    grammars: int = 2,
    pictures: bool = True,
    budget_minutes: float = 30.0,
    db: str | None = None,
    config=None,
) -> pathlib.Path | str:
    """A study of ``grammars`` lattice grammars in ``folder``; its picks have PNG pictures when ``pictures``.
    ``db``: a PostgreSQL URL to create it in instead of ``folder/study.db`` (``folder`` holds its pictures);
    ``config`` a :class:`~ramure.studies.design.StudyConfig` (default: the defaults)."""
    specs = {}
    for g in range(grammars):
        picks = lattice_picks(seed=g + 1)
        if pictures:
            pics = folder / f"set{g}"
            pics.mkdir(parents=True, exist_ok=True)
            for p in picks:
                png(pics / f"pick_{p.id:02d}.png", 9 * p.id)
            picks = [
                dict(id=p.id, variant=p.variant, pca=list(p.pca), params=p.params, image=str(pics / f"pick_{p.id:02d}.png"))
                for p in picks
            ]
        specs[f"g{g}"] = picks
    where = db if db is not None else folder / "study.db"
    Study.create(where, grammars=specs, name="web-study", budget_minutes=budget_minutes, folder=folder, config=config).close()
    return where


def snapshot(db: pathlib.Path | str) -> list[str]:
    """Every row of every table, read through a separate read-only connection (SQLite or PostgreSQL)."""
    if isinstance(db, str) and db.startswith("postgresql://"):
        return pg_snapshot(db)
    conn = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    try:
        return list(conn.iterdump())
    finally:
        conn.close()


class WebParticipant:
    """One participant driving the JSON API: join, then answer each part completely.

    The pages between picture sets (instructions, the practice text, attention checks,
    demographics) are answered as they come (:meth:`pass_pages`) unless ``pages=False``;
    ``pages_seen`` lists their kinds in order.
    """

    def __init__(self, client, external_id: str | None = None, pages: bool = True):
        self.client = client
        body = {"consent": True}
        if external_id:
            body["external_id"] = external_id
        r = client.post("/api/join", json=body)
        assert r.status_code == 200, r.text
        self.code, self.token = r.json()["code"], r.json()["token"]
        self.headers = {"Authorization": f"Bearer {self.token}"}
        self.pages, self.pages_seen = pages, []
        self.state = self.get_state()
        if pages:
            self.pass_pages()

    def pass_pages(self, attention: str = "fair") -> dict:
        """Answer every page of text or questions up to the next picture set or the end: the
        attention check with ``attention``, other questions with their first option."""
        while "page" in self.state:
            page = self.state["page"]
            self.pages_seen.append(page["kind"])
            answers = {
                q["key"]: attention if page["kind"] == "attention" and attention in q["options"] else q["options"][0]
                for q in page["questions"]
            }
            self.send(page=page["kind"], **({"answers": answers} if page["questions"] else {}))
        return self.state

    def get_state(self) -> dict:
        r = self.client.get(f"/api/p/{self.code}/state", headers=self.headers)
        assert r.status_code == 200, r.text
        self.state = r.json()
        return self.state

    def send(self, **body) -> dict:
        body = {"version": self.state["version"], "part": self.state["part"], **body}
        r = self.client.post(f"/api/p/{self.code}/answer", json=body, headers=self.headers)
        assert r.status_code == 200, r.text
        self.state = r.json()
        return self.state

    def answer_part(self, sizes=(9, 9, 8, 1)) -> list[list[str]]:
        """Group the shown pictures in runs of ``sizes``, answer every question, finish."""
        shown, groups, start = self.state["pictures"], [], 0
        for size in sizes:
            groups.append(shown[start : start + size])
            start += size
        self.send(action="groups", groups=groups)
        for label, pics in enumerate(groups, start=1):
            if len(pics) > 1:
                self.send(action="representative", group=label, picture=pics[0])
                self.send(action="rate", group=label, representative_quality=3)
            self.send(action="rate", group=label, usefulness=1 + label % 4, difference=4 - label % 4)
            self.send(action="add_word", group=label, text="small" if label == 1 else "dense")
        self.send(action="finish")
        if self.pages:
            self.pass_pages()
        return groups


def pg_snapshot(url: str) -> list[str]:
    """Every row of every table of the PostgreSQL database ``url``, read through its own connection
    (identity sequences left out: a refused insert may use up an id while storing nothing)."""
    import psycopg

    with psycopg.connect(url, autocommit=True) as conn:
        tables = [
            r[0]
            for r in conn.execute(
                "SELECT table_name FROM information_schema.tables WHERE table_schema = current_schema() ORDER BY table_name"
            )
        ]
        rows = []
        for table in tables:
            rows += [f"{table}: {r!r}" for r in conn.execute(f"SELECT * FROM {table} ORDER BY 1")]  # noqa: S608
        return sorted(rows)
