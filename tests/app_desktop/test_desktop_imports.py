"""The desktop imports Ramure's own packages directly (no ``except ImportError`` hiding a broken
install) and reads the study database only through :class:`ramure.studies.Study`."""

from __future__ import annotations

import ast

from desktop_helpers import ROOT

DESKTOP = ROOT / "app" / "desktop"


def _handlers(tree):
    for node in ast.walk(tree):
        if isinstance(node, ast.Try):
            for h in node.handlers:
                names = [h.type] if not isinstance(h.type, ast.Tuple) else list(h.type.elts)
                if any(isinstance(n, ast.Name) and n.id in ("ImportError", "ModuleNotFoundError") for n in names):
                    yield node


def test_no_import_error_guards_around_ramure_packages():
    offenders = []
    for path in sorted(DESKTOP.rglob("*.py")):  # panels/, view/ and menus/ too
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in _handlers(tree):
            for inner in ast.walk(node):
                if isinstance(inner, ast.ImportFrom) and (inner.module or "").startswith("ramure"):
                    offenders.append(f"{path.relative_to(DESKTOP)}:{inner.lineno}")
    assert offenders == []


def test_the_desktop_runs_no_sql_on_the_study_database():
    paths = sorted(DESKTOP.rglob("*.py"))  # the study screens are in menus/
    assert DESKTOP / "menus" / "study.py" in paths
    for path in paths:
        text = path.read_text(encoding="utf-8")
        assert ".conn.execute(" not in text and "SELECT " not in text, path.name


def test_study_grammar_source_is_public(tmp_path):
    import pytest

    from ramure.studies import Study
    from ramure.errors import RamureError

    assert callable(getattr(Study, "grammar_source", None))
    picks = [
        {"id": i, "variant": i, "pca": [float(i), 0.0, 0.0], "params": {"rule": None, "constants": {"k": float(i)}}}
        for i in range(1, 28)  # 27 different plants: a set of copies is refused
    ]
    study = Study.create(tmp_path / "s.sqlite", grammars={"g": picks})
    assert study.grammar_source("g") is None  # plain pick data: no exploration folder
    with pytest.raises(RamureError):
        study.grammar_source("nope")
    study.close()
