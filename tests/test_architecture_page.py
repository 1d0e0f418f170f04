"""The architecture page cannot rot: the names it cites exist, its table and its drawing are the
layering test's ``ALLOWED`` table.  The names the G-map guide cites are checked the same way."""

from __future__ import annotations

import importlib
import pathlib
import re
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "architecture.md"
sys.path.insert(0, str(ROOT / "docs" / "images"))
import make_architecture  # noqa: E402  (docs/images is not a package)

sys.path.pop(0)


def cited_names(text: str) -> list[str]:
    """Every ``ramure.…`` name the page writes in backticks (``ramure.<base>`` is a placeholder)."""
    return sorted({m for m in re.findall(r"`(ramure(?:\.[A-Za-z_]\w*)*)`", text)})


def resolve(name: str) -> object:
    """The object a dotted name stands for: the longest importable module, then attributes."""
    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError as exc:
            if exc.name is not None and not ".".join(parts[:cut]).startswith(exc.name):
                raise  # a dependency is missing, not the name
            continue
        for attr in parts[cut:]:
            obj = getattr(obj, attr)
        return obj
    raise ModuleNotFoundError(name)


@pytest.mark.parametrize(("page", "least"), [("architecture.md", 40), ("gmap.md", 8)])
def test_every_name_the_page_cites_exists(page, least):
    pytest.importorskip("PySide6")
    names = cited_names((ROOT / "docs" / page).read_text(encoding="utf-8"))
    assert len(names) > least  # the architecture page cites the road through the code, not three names
    missing = []
    for name in names:
        try:
            resolve(name)
        except (ImportError, AttributeError) as exc:
            missing.append(f"{name}: {exc}")
    assert missing == []


def test_the_resolver_refuses_a_name_that_is_gone():
    with pytest.raises(AttributeError):
        resolve("ramure.lsys.regeneration.mincut.no_such_function")
    with pytest.raises((ImportError, AttributeError)):
        resolve("ramure.no_such_package.thing")
    assert resolve("ramure.lsys.regeneration.mincut.select_roots").__name__ == "select_roots"


def test_the_page_table_is_the_layering_table():
    rows = re.findall(r"^\| `(ramure[^`]*)` \| ([^|]*) \|", PAGE.read_text(encoding="utf-8"), re.M)
    table = {name: set(re.findall(r"`([^`]+)`", allowed)) for name, allowed in rows}
    allowed = make_architecture.allowed_table()
    table["ramure.app"] = allowed["ramure.app"] if "every package above" in dict(rows)["ramure.app"] else table["ramure.app"]
    assert table == allowed


def test_the_drawing_is_made_from_the_layering_table():
    committed = (ROOT / "docs" / "images" / "packages.svg").read_text(encoding="utf-8")
    assert committed == make_architecture.svg(make_architecture.allowed_table()), (
        "run docs/images/make_architecture.py and commit docs/images/packages.svg"
    )


def test_floors_and_reduced_edges():
    allowed = {"a": {"b", "c"}, "b": {"c"}, "c": set()}
    assert make_architecture.floors(allowed) == {"a": 2, "b": 1, "c": 0}
    assert make_architecture.reduced_edges(allowed) == [("a", "b"), ("b", "c")]
    real = make_architecture.floors(make_architecture.allowed_table())
    assert real["ramure.app"] == max(real.values()) and real["ramure.<base>"] == 0
    assert real["ramure.gmap.kernel"] < real["ramure.gmap.lsystem"] < real["ramure.gmap.organs"]


def test_the_desktop_rooms_table_and_drawing_are_the_rooms_test():
    text = PAGE.read_text(encoding="utf-8")
    rows = re.findall(r"^\| (command|window|menus|panels|view|controller|helpers) \| ([^|]*) \|", text, re.M)
    table = {name: {r.strip() for r in allowed.split(",")} - {"nothing of the desktop's"} for name, allowed in rows}
    rooms = make_architecture.rooms_table()
    assert table == rooms and len(rooms) == 7
    committed = (ROOT / "docs" / "images" / "desktop.svg").read_text(encoding="utf-8")
    assert committed == make_architecture.svg(rooms, rooms=True), (
        "run docs/images/make_architecture.py and commit docs/images/desktop.svg"
    )
    assert make_architecture.floors(rooms)["window"] > make_architecture.floors(rooms)["panels"]
