"""The desktop window under a (virtual) display: pick, rectangle, regrow, undo, errors, screenshots."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt
from PySide6.QtTest import QTest

from ramure.app.desktop.view.thumbnails import pixel_variance
from desktop_helpers import STOCHASTIC, settle

pytestmark = pytest.mark.gui


def vtk_display(view, point):
    """World -> display through VTK itself (vtkCoordinate), to check the vectorised projection."""
    import vtk

    coord = vtk.vtkCoordinate()
    coord.SetCoordinateSystemToWorld()
    coord.SetValue(*map(float, point))
    return np.array(coord.GetComputedDoubleDisplayValue(view.plotter.renderer))


def isolated_segment(window, candidates):
    """The candidate segment whose projected midpoint is farthest from every other segment's."""
    snap = window.controller.snapshot
    xy = window.view.project(snap.midpoints)
    best, best_gap = None, -1.0
    for i in candidates:
        others = np.delete(np.arange(len(xy)), i)
        gap = float(np.min(np.linalg.norm(xy[others] - xy[i], axis=1)))
        if gap > best_gap:
            best, best_gap = int(i), gap
    return best, xy[best]


def click(window, xy, modifier=Qt.KeyboardModifier.NoModifier):
    QTest.mouseClick(window.view.plotter, Qt.MouseButton.LeftButton, modifier, window.view.to_widget(*xy))


def test_click_on_a_segment_midpoint_selects_its_leaf(make_window, qtbot):
    w = make_window()
    snap = w.controller.snapshot
    trunk = int(np.argmax(snap.skeleton.base_radius))
    xy = w.view.project(snap.midpoints[[trunk]])[0]
    assert np.allclose(xy, vtk_display(w.view, snap.midpoints[trunk])[:2], atol=1.0)
    click(w, xy)
    assert w.controller.explorer.selection == [int(snap.segment_leaf[trunk])]
    # a thin side branch far from the others
    order = np.asarray(snap.skeleton.order)
    seg, xy = isolated_segment(w, np.flatnonzero(order >= 2))
    click(w, xy)
    assert w.controller.explorer.selection == [int(snap.segment_leaf[seg])]
    assert w.view.has_box()  # the selection's OBB is drawn
    rgb = np.asarray(w.view.mesh.cell_data["rgb"])
    picked = np.asarray(w.view.mesh.cell_data["leaf_id"]) == snap.segment_leaf[seg]
    assert (rgb[picked] == [255, 0, 0]).all() and not (rgb[~picked] == [255, 0, 0]).all(axis=1).any()


def test_ctrl_click_toggles_and_escape_clears(make_window):
    w = make_window()
    snap = w.controller.snapshot
    order = np.asarray(snap.skeleton.order)
    a, xa = isolated_segment(w, np.flatnonzero(order == 2))
    b, xb = isolated_segment(w, np.setdiff1d(np.flatnonzero(order >= 3), [a]))
    la, lb = int(snap.segment_leaf[a]), int(snap.segment_leaf[b])
    click(w, xa)
    click(w, xb, Qt.KeyboardModifier.ControlModifier)
    assert w.controller.explorer.selection == sorted({la, lb})
    click(w, xa, Qt.KeyboardModifier.ControlModifier)
    assert w.controller.explorer.selection == [lb]
    QTest.keyClick(w.view.plotter, Qt.Key.Key_Escape)
    assert w.controller.explorer.selection == []
    assert not w.view.has_box()


def test_click_on_background_changes_nothing(make_window):
    w = make_window()
    click(w, w.view.project(w.controller.snapshot.midpoints[:1])[0])
    before = list(w.controller.explorer.selection)
    QTest.mouseClick(w.view.plotter, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, QPoint(3, 3))
    assert w.controller.explorer.selection == before


def drag(window, a, b, button=Qt.MouseButton.RightButton, modifier=Qt.KeyboardModifier.NoModifier):
    plotter = window.view.plotter
    pa, pb = window.view.to_widget(*a), window.view.to_widget(*b)
    QTest.mousePress(plotter, button, modifier, pa)
    QTest.mouseMove(plotter, (pa + pb) / 2)
    QTest.mouseRelease(plotter, button, modifier, pb)


def expected_in_rect(window, rect):
    snap = window.controller.snapshot
    xy = np.array([vtk_display(window.view, p)[:2] for p in snap.midpoints])
    x0, y0, x1, y1 = rect
    inside = (xy[:, 0] >= min(x0, x1)) & (xy[:, 0] <= max(x0, x1)) & (xy[:, 1] >= min(y0, y1)) & (xy[:, 1] <= max(y0, y1))
    return set(np.unique(snap.segment_leaf[inside]).tolist())


def test_rubber_band_selects_the_branches_inside(make_window):
    w = make_window()
    xy = w.view.project(w.controller.snapshot.midpoints)
    lo, hi = np.nanmin(xy, axis=0), np.nanmax(xy, axis=0)
    mid = (lo + hi) / 2
    upper_right = (mid[0], mid[1], hi[0] + 5, hi[1] + 5)
    expected = expected_in_rect(w, upper_right)
    assert 0 < len(expected) < len(set(w.controller.snapshot.segment_leaf.tolist()))
    drag(w, upper_right[:2], upper_right[2:])
    got = set(w.controller.explorer.selection)
    # corners land on whole pixels: allow a midpoint lying on the border to differ
    assert len(got ^ expected) <= 2 and len(got & expected) >= len(expected) - 2
    # Shift adds the lower-left quarter, Ctrl removes it again
    lower_left = (lo[0] - 5, lo[1] - 5, mid[0], mid[1])
    extra = expected_in_rect(w, lower_left)
    drag(w, lower_left[:2], lower_left[2:], modifier=Qt.KeyboardModifier.ShiftModifier)
    assert len(set(w.controller.explorer.selection) ^ (got | extra)) <= 2
    drag(w, lower_left[:2], lower_left[2:], modifier=Qt.KeyboardModifier.ControlModifier)
    assert len(set(w.controller.explorer.selection) ^ (got - extra)) <= 2


def test_rectangle_mode_uses_the_left_button(make_window):
    w = make_window()
    xy = w.view.project(w.controller.snapshot.midpoints)
    lo, hi = np.nanmin(xy, axis=0) - 5, np.nanmax(xy, axis=0) + 5
    w.rect_action.trigger()
    assert w.view.rectangle_mode
    drag(w, lo, hi, button=Qt.MouseButton.LeftButton)
    assert set(w.controller.explorer.selection) == set(w.controller.snapshot.segment_leaf.tolist())


def under(tree, roots):
    """All node ids in the subtrees of ``roots`` (roots included)."""
    return set(np.concatenate([tree.subtree(int(r)) for r in roots]).tolist())


def test_regrow_changes_only_the_cut_subtrees_and_undo_restores(make_window, qtbot):
    w = make_window(STOCHASTIC, n=4)
    ex = w.controller.explorer
    before_string = ex.derivation.to_string()
    before_leaves = ex.derivation.tree.leaves.copy()
    size_before = ex.derivation.tree.size
    snap = w.controller.snapshot
    order = np.asarray(snap.skeleton.order)
    tips = np.flatnonzero(order == order.max())[:6]
    w.controller.select(snap.segment_leaf[tips])
    cut = w.controller.plan()
    doomed = under(ex.derivation.tree, cut.roots)
    qtbot.mouseClick(w.regen.regrow_button, Qt.MouseButton.LeftButton)
    settle(qtbot, w)
    after = ex.derivation.tree.leaves
    assert ex.derivation.to_string() != before_string
    kept_before = [v for v in before_leaves.tolist() if v not in doomed]
    kept_after = [v for v in after.tolist() if v < size_before]
    assert kept_before == kept_after  # every module outside the cut subtrees is untouched, in order
    assert sorted(w.controller.snapshot.last_result.roots.tolist()) == sorted(cut.roots.tolist())
    result = w.controller.snapshot.last_result
    assert f"regrew {result.removed} of {len(before_leaves)} modules" in w.status_label.text()  # the share
    assert "roots [" not in w.status_label.text()  # the user's words, not the algorithm's
    assert w.presenter.drawn_version == w.controller.snapshot.version
    assert w.cut_view.layout_data is not None  # the cut graph dock shows the last cut
    QTest.keyClick(w.view.plotter, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    settle(qtbot, w)
    assert ex.derivation.to_string() == before_string
    assert np.array_equal(ex.derivation.tree.leaves, before_leaves)
    assert w.view.mesh.n_cells == snap.mesh.n_cells
    QTest.keyClick(w.view.plotter, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
    settle(qtbot, w)
    assert [v for v in ex.derivation.tree.leaves.tolist() if v < size_before] == kept_after


def test_prune_and_regrow_with_constants(make_window, qtbot):
    w = make_window(n=7)
    ex = w.controller.explorer
    snap = w.controller.snapshot
    tips = np.flatnonzero(np.asarray(snap.skeleton.order) >= 2)[:8]
    w.controller.select(snap.segment_leaf[tips])
    n_before = len(ex.derivation)
    qtbot.mouseClick(w.regen.prune_button, Qt.MouseButton.LeftButton)
    settle(qtbot, w)
    assert len(ex.derivation) < n_before
    w.controller.undo()
    settle(qtbot, w)
    w.controller.select(snap.segment_leaf[tips])
    w.regen.boxes["a2"].setValue(20.0)
    # the Details dock may still replay its last detail for the undone version: wait for the regrow
    with qtbot.waitSignal(w.controller.job_done, timeout=10000, check_params_cb=lambda job: job.name == "regrow") as blocker:
        qtbot.mouseClick(w.regen.with_constants_button, Qt.MouseButton.LeftButton)
    job = blocker.args[0]
    assert job.error is None and job.name == "regrow"
    assert ex.session.edits[-1]["constants"] == {"a2": 20.0}
    assert ex.constants["a2"] == 60.0  # scoped to the regrown parts, the plant's constant is unchanged


def test_invalid_grammar_shows_the_error_and_keeps_the_plant(make_window, qtbot):
    w = make_window()
    version, cells = w.presenter.drawn_version, w.view.mesh.n_cells
    text = w.editor.text()
    bad = text.replace("F(l)[&(a1)", "F(l*zz)[&(a1)")
    line = next(i for i, t in enumerate(bad.splitlines(), 1) if "zz" in t)
    column = bad.splitlines()[line - 1].index("zz") + 1
    w.editor.edit.setPlainText(bad)
    qtbot.waitUntil(lambda: w.editor.error is not None, timeout=5000)
    settle(qtbot, w)
    assert "zz" in w.editor.message.text()
    assert w.editor.underlined() == (line, column)
    assert w.presenter.drawn_version == version and w.view.mesh.n_cells == cells
    assert w.controller.explorer.document_text() == text  # the model kept the last good grammar
    # fixing it derives the new text and clears the underline
    w.editor.edit.setPlainText(text.replace("#define a2 60", "#define a2 45"))
    qtbot.waitUntil(lambda: w.editor.error is None and w.presenter.drawn_version != version, timeout=5000)
    assert w.editor.underlined() is None and w.controller.explorer.constants["a2"] == 45


def test_stale_results_are_dropped(make_window, qtbot):
    w = make_window()
    text = w.editor.text()
    shown = []
    w.controller.plant_changed.connect(lambda snap: shown.append(snap.text))
    for value in (20, 30, 40, 50):
        w.controller.set_text(text.replace("#define a2 60", f"#define a2 {value}"))
    settle(qtbot, w)
    assert shown and shown[-1] == text.replace("#define a2 60", "#define a2 50")
    assert len(shown) <= 2  # queued edits replaced each other; an overtaken one is not drawn
    assert w.controller.explorer.constants["a2"] == 50


def test_constant_slider_rederives(make_window, qtbot):
    w = make_window()
    version = w.presenter.drawn_version
    old_bounds = w.view.mesh.bounds
    w.constants_panel.set_constant("a2", 20.0)
    qtbot.waitUntil(lambda: w.presenter.drawn_version != version, timeout=5000)
    settle(qtbot, w)
    assert w.controller.explorer.constants["a2"] == 20.0
    assert w.view.mesh.bounds != old_bounds
    assert w.controller.last_job_seconds < 2.0
    w.constants_panel.n_box.setValue(4)
    settle(qtbot, w)
    assert w.controller.explorer.session.n == 4


def test_a_slider_drag_is_one_undo_step(make_window, qtbot):
    w = make_window()
    ex = w.controller.explorer
    before = ex.constants["a2"]
    slider = w.constants_panel.rows["a2"].slider
    slider.setSliderDown(True)  # the user grabs the handle (emits sliderPressed)
    for step in (300, 320, 350, 400):
        slider.setValue(step)
        qtbot.wait(120)  # longer than the settle pause: each value re-derives
        settle(qtbot, w)
    assert len(ex.session.edits) == 1  # the values shown while dragging replaced each other
    slider.setValue(420)
    slider.setSliderDown(False)  # release: the final value is sent at once
    settle(qtbot, w)
    final = w.constants_panel.values()["a2"]
    assert ex.constants["a2"] == final != before and len(ex.session.edits) == 1
    w.constants_panel.set_constant("a2", 45.0)  # a separate change: its own step
    settle(qtbot, w)
    assert len(ex.session.edits) == 2
    w.controller.undo()
    w.controller.undo()
    settle(qtbot, w)
    assert ex.constants["a2"] == before and not ex.session.can_undo
    assert w.constants_panel.values()["a2"] == before


def test_bad_values_are_refused_and_a_crash_keeps_the_plant(make_window, qtbot):
    w = make_window()
    version = w.presenter.drawn_version
    w.controller.set_constant("a2", float("nan"))
    settle(qtbot, w)
    assert "finite" in w.last_message and w.presenter.drawn_version == version

    def boom(ex):
        raise RuntimeError("simulated bug")

    w.controller.submit("boom", boom)
    settle(qtbot, w)
    assert "simulated bug" in w.last_message and w.presenter.drawn_version == version
    w.controller.select([])
    w._prune()
    assert "select" in w.last_message


def test_kinship_mode_colours_by_hue(make_window):
    w = make_window()
    snap = w.controller.snapshot
    leaf = int(snap.segment_leaf[len(snap.segment_leaf) // 2])
    w.controller.select([leaf])
    w.set_kinship(True)
    rgb = np.asarray(w.view.mesh.cell_data["rgb"])
    mine = np.asarray(w.view.mesh.cell_data["leaf_id"]) == leaf
    assert (rgb[mine] == [255, 0, 0]).all()
    assert len(np.unique(rgb, axis=0)) > 3 and (rgb[:, 2] > 200).any()  # hues reach blue
    assert w.statusBar().currentMessage().startswith("Kinship colours: red = the selected leaf")
    w.controller.select(snap.segment_leaf[:3].tolist())
    assert "exactly one" in w.statusBar().currentMessage()
    w.set_kinship(False)
    assert len(np.unique(np.asarray(w.view.mesh.cell_data["rgb"]), axis=0)) <= 4


def test_window_screenshot_is_not_blank(make_window, artifacts):
    w = make_window(n=8)
    snap = w.controller.snapshot
    w.controller.select(snap.segment_leaf[np.flatnonzero(np.asarray(snap.skeleton.order) == 2)[:20]])
    image = w.grab_window()
    path = artifacts / "desktop_window.png"
    assert image.save(str(path))
    assert pixel_variance(image) > 100.0
    view = w.view.grab_image()
    view.save(str(artifacts / "desktop_view.png"))
    assert pixel_variance(view) > 20.0
    arr = np.frombuffer(view.convertToFormat(view.Format.Format_RGB888).constBits(), np.uint8)
    stride = view.convertToFormat(view.Format.Format_RGB888).bytesPerLine()
    pix = arr.reshape(view.height(), stride)[:, : view.width() * 3].reshape(view.height(), view.width(), 3)
    red = (pix[..., 0] > 180) & (pix[..., 1] < 80) & (pix[..., 2] < 80)
    assert red.sum() > 20  # the selection is drawn red


def test_constant_ranges_are_inferred_and_editable(make_window, qtbot):
    w = make_window()
    row = w.constants_panel.rows["a2"]
    assert (row.lo, row.hi) == (0.0, 120.0)
    w.constants_panel.edit_ranges.setChecked(True)
    assert row.low.isVisibleTo(w.constants_panel)
    row.high.setValue(90.0)
    assert row.hi == 90.0 and row.slider.value() == round(60 / 90 * 1000)
    refused = []
    w.constants_panel.range_refused.connect(refused.append)
    row.low.setValue(95.0)  # above the maximum: refused, the range stays
    assert refused[-1] and row.lo == 0.0 and row.low.value() == 0.0
    row.value.setValue(150.0)  # typing outside the range widens it
    assert row.hi == 150.0
    qtbot.waitUntil(lambda: w.controller.explorer.constants["a2"] == 150.0, timeout=5000)


def test_the_ui_keeps_running_during_a_long_job(make_window, qtbot):
    import time

    w = make_window()
    ticks = []
    from PySide6.QtCore import QTimer

    timer = QTimer()
    timer.timeout.connect(lambda: ticks.append(time.perf_counter()))
    timer.start(20)
    w.controller.submit("slow", lambda ex: time.sleep(0.6))
    settle(qtbot, w)
    timer.stop()
    assert len(ticks) >= 10  # the event loop ran all along


def test_an_exception_in_a_slot_is_reported_not_fatal(make_window):
    import sys

    w = make_window()
    try:
        raise ZeroDivisionError("oops")
    except ZeroDivisionError:
        w.report_unexpected(*sys.exc_info())
    assert "oops" in w.last_message and w.isVisible()


def test_wide_cut_graph_stays_readable(make_window, qtbot, artifacts):
    from PySide6.QtCore import QRect

    w = make_window(n=8)
    snap = w.controller.snapshot
    w.controller.select(snap.segment_leaf[len(snap.segment_leaf) // 3 :])
    w.controller.regrow(seed=3)
    settle(qtbot, w)
    w.open_dock("cut")  # closed at start: opened as the View menu does
    settle(qtbot, w)
    cut = w.cut_view
    layout = cut.layout_data
    assert len(cut.labels) > 100
    assert cut.labels_shown() > 20  # fitted to the height, not shrunk to an unreadable line

    def rects():
        out = []
        for text in cut.labels:
            if text.isVisible():
                top_left = cut.view.mapFromScene(text.pos())
                size = text.boundingRect().size().toSize()
                out.append(QRect(top_left, size))
        return out

    shown = rects()
    assert not any(a.intersects(b) for i, a in enumerate(shown) for b in shown[i + 1 :])
    for _ in range(6):
        cut.zoom(1 / 1.15)
    assert cut.labels_shown() < len(shown) and "zoom in" in cut.hint.text()
    shown = rects()
    assert not any(a.intersects(b) for i, a in enumerate(shown) for b in shown[i + 1 :])
    node = next(v for v in layout.positions if isinstance(v, tuple))
    assert f"node {node[0]} (" in cut._tooltip(layout, node, node in layout.source_side)
    w.grab_window().save(str(artifacts / "desktop_cut_graph.png"))


def test_the_cut_docks_plan_button_plans_the_selection(make_window, qtbot):
    # the dock plans by itself (the window only connects its signals): no selection, a sentence;
    # a selection, its graph with the roots the model plans, and the closed dock opened in front
    w = make_window(n=6)
    cut = w.cut_view
    assert not w.docks["cut"].isVisible()  # closed at start
    cut.plan_button.click()
    assert cut.title.text() == "Select branches first: the cut is planned for the selection."
    assert cut.layout_data is None and not w.docks["cut"].isVisible()
    snap = w.controller.snapshot
    w.controller.select(snap.segment_leaf[-3:])
    settle(qtbot, w)
    planned = w.controller.explorer.plan()
    cut.plan_button.click()
    assert cut.layout_data is not None and w.docks["cut"].isVisible()
    assert cut.title.text().startswith(f"Planned cut for the selection: roots {planned.roots.tolist()[:12]}")
