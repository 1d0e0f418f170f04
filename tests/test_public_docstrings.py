"""Every public function of the CLI commands, the Jupyter widgets and the desktop has a docstring
(issue 41), checked with .ci/public_docstrings.py."""

import pathlib
import runpy
from types import SimpleNamespace

ROOT = pathlib.Path(__file__).resolve().parents[1]

#: Left undocumented on purpose: ``app/jupyter/variants.py`` was being reworked by the qualifier
#: work of issue 41 when these docstrings were written; document them there, then drop them here.
NOT_YET = {"app/jupyter/variants.py: VariantPanel.pick_point", "app/jupyter/variants.py: VariantPanel.refresh"}


def _script():
    """The checker's namespace (``scan``, ``coverage``, ``FOLDERS``), run from its file."""
    return SimpleNamespace(**runpy.run_path(str(ROOT / ".ci" / "public_docstrings.py")))


def test_the_detector_finds_what_it_should(tmp_path):
    source = tmp_path / "m.py"
    source.write_text(
        'def told():\n    """Says."""\n'
        "def silent(a): ...\n"
        "def _private(a): ...\n"
        "class C:\n"
        "    def __init__(self, x): ...\n"
        "    @property\n"
        '    def size(self):\n        """Told."""\n'
        "    @size.setter\n"
        "    def size(self, value): ...\n"
        "    def method(self):\n"
        "        def inner(q): ...\n"
        "class _Hidden:\n"
        "    def method(self, y): ...\n"
    )
    total, found = _script().scan(source)
    assert total == 5  # told, silent, size, size (the setter), method
    assert [line.split(": ", 1)[1] for line in found] == ["silent", "C.size", "C.method"]


def test_every_public_function_has_a_docstring():
    script = _script()
    assert "app/desktop" in script.FOLDERS  # with its panels/, view/ and menus/
    total, missing = script.coverage([str(ROOT / f) for f in script.FOLDERS])
    missing = {line.replace(str(ROOT) + "/", "") for line in missing}
    assert total > 600  # the commands, the widgets and the desktop (412 alone), not an empty folder
    assert sorted(missing - NOT_YET) == [], "public functions without a docstring"
    assert (total - len(missing)) / total >= 0.99
