"""The desktop shows what a selection will change before it changes (issue 34, section 2): clicks,
the ρ slider and the Regrow and Apply buttons driven with real Qt events."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtTest import QTest

from ramure.app.desktop.state import CUT_PREVIEW
from desktop_helpers import settle

pytestmark = pytest.mark.gui


def click(window, xy, modifier=Qt.KeyboardModifier.NoModifier):
    QTest.mouseClick(window.view.plotter, Qt.MouseButton.LeftButton, modifier, window.view.to_widget(*xy))


def twig_and_tip(window):
    """A segment made one step before the tips, one of the two tips it carries (their leaves) and
    where to click them: the pair whose points lie farthest from every other segment's."""
    snap = window.controller.snapshot
    tree = window.controller.explorer.derivation.tree
    xy = window.view.project(snap.midpoints)
    seg_of = {int(leaf): i for i, leaf in enumerate(snap.segment_leaf.tolist())}
    order = np.asarray(snap.skeleton.order)
    best, best_gap = None, -1.0
    for i in np.flatnonzero(order == order.max()).tolist():
        tip = int(snap.segment_leaf[i])
        below = tree.children(int(tree.parent[int(tree.parent[tip])]))
        carrier = [int(v) for v in below if int(v) in seg_of]
        if len(carrier) != 1:
            continue
        j = seg_of[carrier[0]]
        gap = min(float(np.min(np.linalg.norm(np.delete(xy, k, axis=0) - xy[k], axis=1))) for k in (i, j))
        if gap > best_gap:
            best, best_gap = (carrier[0], tip, xy[j], xy[i]), gap
    return best


def colours(window):
    mesh = window.view.mesh
    return np.asarray(mesh.cell_data["rgb"]), np.asarray(mesh.cell_data["leaf_id"])


def test_a_click_shows_the_cut_and_its_share_and_regrow_changes_exactly_that(make_window, qtbot):
    w = make_window(n=6)
    snap = w.controller.snapshot
    assert not w.regen.cut_preview.isVisible()
    # the trunk's first segment carries the whole plant: nothing would change, and it says why
    trunk = int(np.argmax(snap.skeleton.base_radius))
    click(w, w.view.project(snap.midpoints[[trunk]])[0])
    settle(qtbot, w)
    assert w.regen.cut_preview.isVisible()
    assert w.regen.cut_preview.text().startswith("nothing will change: the selected leaf carries branches")
    before = w.controller.explorer.derivation.to_string()
    qtbot.mouseClick(w.regen.regrow_button, Qt.MouseButton.LeftButton)
    settle(qtbot, w)
    assert "nothing regrows" in w.last_message and w.controller.explorer.derivation.to_string() == before
    # a twig's segment and one of its two tips, clicked: 2 of the twig's 3 segments are picked,
    # so the twig regrows whole; its other tip, not selected, shows orange
    ex = w.controller.explorer
    tree = ex.derivation.tree
    segment, tip, xy_segment, xy_tip = twig_and_tip(w)
    click(w, xy_segment)
    click(w, xy_tip, Qt.KeyboardModifier.ControlModifier)
    settle(qtbot, w)
    assert ex.selection == sorted([segment, tip])
    twig = int(tree.parent[segment])
    shown = ex.preview()
    assert shown.roots.tolist() == [twig] and shown.changed == len(tree.leaves_under(twig)) == 34
    assert w.regen.cut_preview.text() == (
        "34 of 693 modules (4.9 %) will change, the cut climbs 1-2 levels above the selected leaves"
    )
    rgb, leaves = colours(w)
    orange = (rgb == CUT_PREVIEW).all(axis=1)
    other_tip = np.setdiff1d(np.intersect1d(tree.leaves_under(twig), w.controller.snapshot.segment_leaf), [segment, tip])
    assert orange.any() and np.unique(leaves[orange]).tolist() == other_tip.tolist()
    assert (rgb[np.isin(leaves, [segment, tip])] == [255, 0, 0]).all()  # the selection stays red
    # ρ up to 100 % with the keyboard: only the tip regrows, the segment stays and it is said
    w.regen.rho.setFocus()
    for _ in range(5):
        QTest.keyClick(w.regen.rho, Qt.Key.Key_PageUp)
    settle(qtbot, w)
    assert w.regen.rho.value() == 100 and ex.rho == pytest.approx(1.0)
    assert w.regen.cut_preview.text().startswith(
        "12 of 693 modules (1.7 %) will change, the cut climbs 1 level above the selected leaves; 1 selected leaf stays"
    )
    assert not (colours(w)[0] == CUT_PREVIEW).all(axis=1).any()  # the other tip is not in the cut now
    for _ in range(5):
        QTest.keyClick(w.regen.rho, Qt.Key.Key_PageDown)
    settle(qtbot, w)
    assert ex.rho == pytest.approx(0.5) and ex.preview().roots.tolist() == [twig]
    qtbot.mouseClick(w.regen.regrow_button, Qt.MouseButton.LeftButton)
    settle(qtbot, w)
    result = w.controller.snapshot.last_result
    assert result.roots.tolist() == shown.roots.tolist() and result.removed == shown.changed
    status = w.status_label.text()
    assert f"regrew {result.removed} of 693 modules" in status and "the cut climbed" in status
    assert w.controller.explorer.selection  # the regrown part stays selected, with its own preview
    assert w.regen.cut_preview.text() == w.controller.explorer.preview().message


def test_a_qualifier_on_a_selection_changes_its_cut_only_and_keeps_it_selected(make_window, qtbot, tmp_path, monkeypatch):
    monkeypatch.setenv("RAMURE_CACHE", str(tmp_path / "cache"))
    w = make_window(n=5)
    ex = w.controller.explorer
    tree = ex.derivation.tree
    twig = int(np.flatnonzero((tree.depth == 2) & tree.alive & (tree.child_count > 0))[-1])
    w.controller.select(tree.leaves_under(twig).tolist())
    settle(qtbot, w)
    assert w.regen.cut_preview.text().startswith("78 of 341 modules (23 %) will change")
    w.regen.qualifier.setCurrentText("thick")  # "dense" adds segments (issue 35): no constant of Honda does
    with qtbot.waitSignal(w.controller.job_done, timeout=60000, check_params_cb=lambda job: job.name == "qualifier thick"):
        qtbot.mouseClick(w.regen.apply_button, Qt.MouseButton.LeftButton)
    settle(qtbot, w)
    result = w.variants.last_qualifier
    assert result.improved and result.roots.tolist() == [twig]  # what the preview showed, nothing more
    added = np.asarray(result.regen.change.added)
    assert ex.selection == sorted(added[tree.child_count[added] == 0].tolist())  # kept selected
    assert f"regrew {result.regen.removed} of 341 modules" in w.status_label.text()
    assert w.regen.cut_preview.text() == ex.preview().message
