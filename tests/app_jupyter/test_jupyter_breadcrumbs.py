"""The derivation-tree and architecture browsers are one breadcrumb list (issue 41), driven by its buttons."""

from __future__ import annotations

from jupyter_helpers import ROOT

from ramure.app.jupyter import NotebookExplorer
from ramure.app.jupyter._ui import Breadcrumbs
from ramure.app.jupyter.architecture import ArchitectureBrowser
from ramure.app.jupyter.selection import TreeBrowser


def _click(browser, name):
    dict(zip(("open", "up", "top", "select"), browser.buttons))[name].click()


def test_the_walk_is_written_once():
    for cls in (TreeBrowser, ArchitectureBrowser):
        assert issubclass(cls, Breadcrumbs)
        assert not {"up", "top", "open_selected", "select", "select_selected"} & set(vars(cls))


def test_the_tree_browser_walks_by_its_buttons(explorer):
    tb = explorer.tree
    _click(tb, "select")  # nothing chosen
    assert explorer.message.text == "choose a row in the derivation tree first" and explorer.selection == []
    tb.rows.value = 0  # the axiom A(1,10): node 0, which is falsy
    _click(tb, "open")
    assert tb.path == [0] and "A(1,10)" in tb.crumbs.value
    leaf = tb.children_with("F")[0]
    tb.rows.value = leaf
    _click(tb, "open")  # a leaf has no children
    assert tb.path == [0] and "a leaf has no children" in tb.info.value
    _click(tb, "select")
    assert explorer.selection == [leaf]
    _click(tb, "up")
    assert tb.path == [] and tb.crumbs.value.endswith("axiom")


def test_the_architecture_browser_walks_by_its_buttons():
    ex = NotebookExplorer(str(ROOT / "grammars" / "amap" / "massart.lsys"), n=4, view="static", size=(120, 120), cache=False)
    arch = ex.architecture
    _click(arch, "select")
    assert ex.message.text == "choose a row in the architecture first" and ex.selection == []
    arch.rows.value = ("axis", 0)
    _click(arch, "open")
    assert arch.path == [("axis", 0)] and "axis 1" in arch.crumbs.value
    arch.rows.value = ("shoot", 0)
    _click(arch, "open")
    arch.rows.value = ("unit", 0)
    _click(arch, "open")
    internode = arch.rows.options[0][1]
    arch.rows.value = internode
    _click(arch, "open")  # an internode has no parts
    assert [kind for kind, _ in arch.path] == ["axis", "shoot", "unit"]
    _click(arch, "select")
    assert ex.selection == arch.leaves_of(internode) and len(ex.selection) == 1
    _click(arch, "top")
    assert arch.path == [] and arch.rows.options[0][1] == ("axis", 0)
