"""Draw the package graph of ``tests/test_layering.py`` as ``docs/images/packages.svg``, and the
desktop's rooms of ``tests/app_desktop/test_desktop_rooms.py`` as ``docs/images/desktop.svg``.

Each drawing is made from its test's ``ALLOWED`` table, so the picture and the rule the
suite enforces are one thing; ``tests/test_architecture_page.py`` fails when a committed
picture is not what this script writes.  Run from the repository root::

    .venv/bin/python docs/images/make_architecture.py

Floors: a package stands one floor above the highest package it may import.  An arrow
"A -> B" says A may import B; arrows implied by two others (A -> B -> C makes A -> C
needless) are left out, the page's table lists them all.
"""

from __future__ import annotations

import ast
import pathlib

import ramure.io

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]
LAYERING = ROOT / "tests" / "test_layering.py"
OUT = HERE / "packages.svg"
ROOMS = ROOT / "tests" / "app_desktop" / "test_desktop_rooms.py"
ROOMS_OUT = HERE / "desktop.svg"

BOX_W, BOX_H, GAP_X, GAP_Y, MARGIN = 170, 34, 36, 56, 20
#: Where each package stands across its floor (in box widths), chosen so that no arrow
#: crosses a box: the front ends above the middle, gmap's rooms in a column on the right.
COLUMN = {"ramure.app": 1.5, "ramure.studies": 1.2, "ramure": 0, "ramure.metrics": 1, "ramure.lsys": 1.5}
COLUMN |= {"ramure.grammars": 1, "ramure.<base>": 1.5}
COLUMN |= {"ramure.gmap": 3, "ramure.gmap.organs": 3, "ramure.gmap.lsystem": 3, "ramure.gmap.kernel": 3}
#: The desktop's rooms: one column, the view and the controller side by side.
ROOM_COLUMN = {"command": 1, "window": 1, "menus": 1, "panels": 1, "view": 0.5, "controller": 1.5, "helpers": 1}


def allowed_table(path: pathlib.Path = LAYERING) -> dict[str, set[str]]:
    """``ALLOWED`` of the layering test, read from its source (the test module is not run)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names: dict[str, object] = {}
    for node in tree.body:
        if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name):
            target = node.targets[0].id
            if target == "BASE":
                names["BASE"] = ast.literal_eval(node.value)
            if target == "ALLOWED":
                source = ast.unparse(node.value).replace("BASE", repr(names["BASE"]))
                return {k: set(v) for k, v in eval(source, {"__builtins__": {}, "set": set}).items()}  # noqa: S307 (our own file)
    raise LookupError(f"no ALLOWED table in {path}")


def rooms_table(path: pathlib.Path = ROOMS) -> dict[str, set[str]]:
    """``ALLOWED`` of the desktop rooms test: ``{room: rooms it may import}``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name) and node.targets[0].id == "ALLOWED":
            source = ast.unparse(node.value)
            return {k: set(v) for k, v in eval(source, {"__builtins__": {}, "set": set}).items()}  # noqa: S307 (our own file)
    raise LookupError(f"no ALLOWED table in {path}")


def floors(allowed: dict[str, set[str]]) -> dict[str, int]:
    """Floor of each package: 0 for those that import nothing of Ramure's, else one above the highest."""
    out: dict[str, int] = {}

    def floor(name: str) -> int:
        if name not in out:
            out[name] = 1 + max((floor(t) for t in allowed[name]), default=-1)
        return out[name]

    for name in allowed:
        floor(name)
    return out


def reduced_edges(allowed: dict[str, set[str]]) -> list[tuple[str, str]]:
    """The edges of ``allowed`` not implied by a path of two or more others (transitive reduction)."""

    def reach(name: str) -> set[str]:
        seen, todo = set(), list(allowed[name])
        while todo:
            t = todo.pop()
            if t not in seen:
                seen.add(t)
                todo += allowed[t]
        return seen

    edges = []
    for a in sorted(allowed):
        implied = set().union(*(reach(b) for b in allowed[a])) if allowed[a] else set()
        edges += [(a, b) for b in sorted(allowed[a]) if b not in implied]
    return edges


def columns(allowed: dict[str, set[str]], level: dict[str, int], hint: dict[str, float] | None = None) -> dict[str, float]:
    """Column of each package: ``hint`` (:data:`COLUMN`) where it says, else the next free one on its floor."""
    hint = COLUMN if hint is None else hint
    out = {name: hint[name] for name in allowed if name in hint}
    for name in sorted(set(allowed) - set(out)):
        out[name] = 1 + max((c for n, c in out.items() if level[n] == level[name]), default=-1)
    return out


def _package_fill(name: str) -> str:
    """gmap's rooms green, the front ends orange, the rest blue."""
    return "#e8f1e4" if name.startswith("ramure.gmap") else "#e6eef7" if name != "ramure.app" else "#f7ece1"


def _room_fill(name: str) -> str:
    """Rooms with widgets orange, the window darker; the Qt-free helpers blue."""
    return {"window": "#f2d9bf", "helpers": "#e6eef7", "controller": "#e6eef7"}.get(name, "#f7ece1")


def svg(allowed: dict[str, set[str]], rooms: bool = False) -> str:
    """The drawing: one row per floor, the top floor first, arrows from importer to imported
    (``rooms``: the desktop's rooms, else Ramure's packages)."""
    level = floors(allowed)
    column = columns(allowed, level, ROOM_COLUMN if rooms else None)
    fill_of = _room_fill if rooms else _package_fill
    title = "The desktop's rooms and the imports each may make" if rooms else "Ramure's packages and the imports each may make"
    top, left = max(level.values()), min(column.values())
    where = {n: (MARGIN + (column[n] - left) * (BOX_W + GAP_X), MARGIN + (top - level[n]) * (BOX_H + GAP_Y)) for n in allowed}
    width = max(x for x, _ in where.values()) + BOX_W + MARGIN
    height = MARGIN * 2 + (top + 1) * (BOX_H + GAP_Y) - GAP_Y
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0f}" height="{height:.0f}" '
        f'viewBox="0 0 {width:.0f} {height:.0f}" font-family="sans-serif" font-size="13">',
        f"<title>{title}</title>",
        '<defs><marker id="arrow" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="7" '
        'markerHeight="7" orient="auto"><path d="M0,0 L10,5 L0,10 z" fill="#555"/></marker></defs>',
        f'<rect width="{width:.0f}" height="{height:.0f}" fill="white"/>',
    ]
    for a, b in reduced_edges(allowed):
        (xa, ya), (xb, yb) = where[a], where[b]
        x0, y0, x1, y1 = xa + BOX_W / 2, ya + BOX_H, xb + BOX_W / 2, yb
        bend = (y1 - y0) / 2
        out.append(
            f'<path d="M{x0:.0f},{y0:.0f} C{x0:.0f},{y0 + bend:.0f} {x1:.0f},{y1 - bend:.0f} {x1:.0f},{y1:.0f}" '
            'fill="none" stroke="#555" stroke-width="1.3" marker-end="url(#arrow)"/>'
        )
    for name, (x, y) in where.items():
        fill = fill_of(name)
        out.append(f'<rect x="{x:.0f}" y="{y:.0f}" width="{BOX_W}" height="{BOX_H}" rx="6" fill="{fill}" stroke="#333"/>')
        label = name.replace("<", "&lt;").replace(">", "&gt;")
        out.append(f'<text x="{x + BOX_W / 2:.0f}" y="{y + BOX_H / 2 + 4:.0f}" text-anchor="middle">{label}</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"


def main() -> None:
    ramure.io.write_text(OUT, svg(allowed_table()))
    ramure.io.write_text(ROOMS_OUT, svg(rooms_table(), rooms=True))
    print(f"wrote {OUT} and {ROOMS_OUT}")


if __name__ == "__main__":
    main()
