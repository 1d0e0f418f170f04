"""List public functions and methods that lack a docstring, and the share that have one.

Public: as in ``public_hints.py``, a name not starting with '_', in a module whose own name
and enclosing class names do not start with '_'; ``__init__`` and other dunders are left to
their class's docstring. Nested functions are skipped.  A property's setter counts as its own
method (it says what assigning does).

Usage: python .ci/public_docstrings.py [FOLDER ...]   (default: app/commands, app/jupyter, app/desktop);
exit 1 when anything is listed.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

#: the folders whose every public function has a docstring (tests/test_public_docstrings.py)
FOLDERS = ("app/commands", "app/jupyter", "app/desktop")


def scan(path: Path) -> tuple[int, list[str]]:
    """``(public functions, "path: Class.name" of those without a docstring)`` of one file."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    total, found = 0, []

    def walk(body: list[ast.stmt], prefix: str) -> None:
        nonlocal total
        for node in body:
            if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                walk(node.body, prefix + node.name + ".")
            elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and not node.name.startswith("_"):
                total += 1
                if ast.get_docstring(node) is None:
                    found.append(f"{path}: {prefix}{node.name}")

    walk(tree.body, "")
    return total, found


def files(folders: list[str]) -> list[Path]:
    """The public modules under ``folders`` (no part of their path starts with '_', but ``__init__``)."""
    out = []
    for folder in folders:
        for path in sorted(Path(folder).rglob("*.py")):
            if not any(part.startswith("_") and part != "__init__.py" for part in path.relative_to(folder).parts):
                out.append(path)
    return out


def coverage(folders: list[str]) -> tuple[int, list[str]]:
    """``(public functions, those without a docstring)`` over ``folders``."""
    total, missing = 0, []
    for path in files(folders):
        count, found = scan(path)
        total, missing = total + count, missing + found
    return total, missing


def main(argv: list[str]) -> int:
    folders = argv or list(FOLDERS)
    total, missing = coverage(folders)
    print("\n".join(missing))
    share = 100 * (total - len(missing)) / max(total, 1)
    print(f"{total - len(missing)} of {total} public functions have a docstring ({share:.0f} %)")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
