"""The grammars shipped with Ramure, as package data.

>>> import ramure.grammars as g
>>> "honda_sympodial" in g.names()
True
>>> g.path("honda_sympodial").name
'honda_sympodial.lsys'
"""
from __future__ import annotations

import pathlib

from ramure.errors import ValueRefused

FOLDER = pathlib.Path(__file__).resolve().parent
SUFFIXES = (".lsys",)


def names() -> list[str]:
    """Names of the shipped grammars (file stems), sorted."""
    return sorted(p.stem for p in FOLDER.iterdir() if p.suffix in SUFFIXES)


def path(name: str) -> pathlib.Path:
    """The file of the shipped grammar ``name`` (a stem such as ``"honda_sympodial"``)."""
    stem = pathlib.Path(name).stem if name.endswith(SUFFIXES) else name
    file = FOLDER / f"{stem}.lsys"
    if not file.is_file():
        raise ValueRefused(f"no shipped grammar named {name!r}; known: {', '.join(names())}")
    return file


def resolve(name_or_path: str | pathlib.Path) -> pathlib.Path:
    """A grammar file: ``name_or_path`` if it exists, else the shipped grammar it names.

    ``"grammars/honda_sympodial.lsys"`` and ``"honda_sympodial"`` both work from any
    directory; a path that exists always wins over a shipped name.
    """
    given = pathlib.Path(name_or_path)
    if given.exists():
        return given
    if given.parent.name in ("", "grammars") and given.suffix in ("",) + SUFFIXES:
        try:
            return path(given.name)
        except ValueRefused:
            pass
    return given
