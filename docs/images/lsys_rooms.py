"""Print the import graph of ``ramure.lsys`` as text: its rooms, their floors, arrows and cycles.

Read from the source (``ast``), lazy (function-level) imports included and imports under ``if
TYPE_CHECKING:`` left out, as ``tests/test_layering.py`` reads it.  A room is a sub-package of
``lsys/``; the modules directly in ``lsys/`` form the room ``<root>``.  Run from the repository
root::

    .venv/bin/python docs/images/lsys_rooms.py            # rooms
    .venv/bin/python docs/images/lsys_rooms.py --modules  # every module, grouped by room

Floors: a room (module) stands one floor above the highest one it imports; a cycle has no
floor and is listed instead.  An arrow ``A -> B, C`` says A imports B and C.
"""

from __future__ import annotations

import argparse
import ast
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
PACKAGE = "ramure.lsys"


def modules(root: pathlib.Path = ROOT) -> dict[str, pathlib.Path]:
    """``{dotted name: path}`` of the modules of ``lsys/`` (``__init__`` named by its package)."""
    out = {}
    for path in sorted((root / "lsys").rglob("*.py")):
        parts = path.relative_to(root / "lsys").with_suffix("").parts
        out[".".join((PACKAGE, *parts)).removesuffix(".__init__")] = path
    return out


def imports(name: str, path: pathlib.Path, known: dict[str, pathlib.Path]) -> set[str]:
    """The lsys modules ``name`` imports, lazy imports included (not those under TYPE_CHECKING)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skip = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skip |= {id(sub) for stmt in node.body for sub in ast.walk(stmt)}
    here = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            parts = here.split(".")
            base = ".".join(parts[: len(parts) - node.level + 1]) if node.level else ""
            source = ".".join(filter(None, (base, node.module)))
            submodules = {f"{source}.{alias.name}" for alias in node.names} & known.keys()
            found |= submodules if len(submodules) == len(node.names) else {source} | submodules
    return {m for m in found if m in known and m != name}


def room(module: str, known: dict[str, pathlib.Path]) -> str:
    """The room of an lsys module: its sub-package, ``<root>`` for the modules of ``lsys/``,
    ``ramure.lsys`` for the front door."""
    if module == PACKAGE:
        return PACKAGE
    rest = module.removeprefix(PACKAGE + ".").split(".")
    return "<root>" if len(rest) == 1 and known[module].name != "__init__.py" else rest[0]


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one node, each sorted."""
    order, seen = [], set()
    for start in graph:
        if start in seen:
            continue
        stack = [(start, iter(sorted(graph[start])))]
        seen.add(start)
        while stack:
            node, children = stack[-1]
            child = next((c for c in children if c not in seen), None)
            if child is None:
                stack.pop()
                order.append(node)
            else:
                seen.add(child)
                stack.append((child, iter(sorted(graph.get(child, ())))))
    reverse: dict[str, set[str]] = {n: set() for n in graph}
    for a, targets in graph.items():
        for b in targets:
            reverse.setdefault(b, set()).add(a)
    out, done = [], set()
    for node in reversed(order):
        if node in done:
            continue
        component, todo = set(), [node]
        while todo:
            n = todo.pop()
            if n not in done:
                done.add(n)
                component.add(n)
                todo += reverse[n] - done
        if len(component) > 1:
            out.append(sorted(component))
    return sorted(out)


def floors(graph: dict[str, set[str]]) -> dict[str, int]:
    """Floor of each node outside a cycle: 0 when it imports nothing, else one above the highest."""
    in_cycle = {n for c in cycles(graph) for n in c}
    out: dict[str, int] = {}

    def floor(node: str, path: tuple[str, ...] = ()) -> int:
        if node not in out:
            if node in in_cycle or node in path:
                return -1
            below = [floor(t, (*path, node)) for t in graph[node]]
            out[node] = -1 if -1 in below else 1 + max(below, default=-1)
        return out[node]

    for node in graph:
        floor(node)
    return {n: f for n, f in out.items() if f >= 0}


def room_graph(root: pathlib.Path = ROOT) -> dict[str, set[str]]:
    known = modules(root)
    graph: dict[str, set[str]] = {}
    for name, path in known.items():
        here = room(name, known)
        graph.setdefault(here, set()).update(room(t, known) for t in imports(name, path, known) if room(t, known) != here)
    return graph


def module_graph(root: pathlib.Path = ROOT) -> dict[str, set[str]]:
    known = modules(root)
    short = {name: name.removeprefix(PACKAGE + ".") for name in known}
    return {short[name]: {short[t] for t in imports(name, path, known)} for name, path in known.items()}


def report(graph: dict[str, set[str]], title: str) -> str:
    """Floors (top first), arrows and cycles of ``graph`` as text."""
    levels = floors(graph)
    lines = [f"{title}: {len(graph)} nodes, {sum(map(len, graph.values()))} arrows"]
    for level in sorted(set(levels.values()), reverse=True):
        lines.append(f"  floor {level}: {', '.join(sorted(n for n, f in levels.items() if f == level))}")
    lines.append("  arrows:")
    lines += [f"    {a} -> {', '.join(sorted(graph[a]))}" for a in sorted(graph) if graph[a]]
    found = cycles(graph)
    lines.append("  cycles: " + ("none" if not found else "; ".join(" <-> ".join(c) for c in found)))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modules", action="store_true", help="the module graph, not the rooms")
    parser.add_argument("--root", type=pathlib.Path, default=ROOT, help="a checkout of Ramure (default: this one)")
    args = parser.parse_args(argv)
    graph = module_graph(args.root) if args.modules else room_graph(args.root)
    print(report(graph, "ramure.lsys modules" if args.modules else "ramure.lsys rooms"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
