"""Variants in the window: exploration with progress and cancel, gallery, PCA dock, qualifiers, fruit."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt

from ramure.app.desktop.state import FRUIT_SELECTED
from ramure.app.desktop.view.thumbnails import pixel_variance
from desktop_helpers import ROOT, settle

pytestmark = pytest.mark.gui


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("RAMURE_CACHE", str(tmp_path / "cache"))


def explored(qtbot, w, n_jobs=1):
    w.variants.explore(n_jobs=n_jobs)
    assert w.progress.isVisible() and w.cancel_button.isVisible()
    qtbot.waitUntil(lambda: w.variants.variant_set is not None and not w.variants.busy(), timeout=60000)
    settle(qtbot, w)
    return w.variants.variant_set


def menu_action(window, menu_title, text):
    """The QAction named ``text`` in the menu bar's ``menu_title`` menu (what a user clicks)."""
    for top in window.menuBar().actions():
        if top.text().replace("&", "") == menu_title:
            for action in top.menu().actions():
                if action.text().replace("&", "") == text:
                    return action
    raise AssertionError(f"no {menu_title} > {text}")


def test_explore_fills_the_gallery_and_the_pca_dock(make_window, qtbot, artifacts):
    w = make_window(n=4)
    # no exploration yet: the dock says so, and has no (empty) matplotlib canvas yet
    assert w.pca_view.canvas is None and "No exploration yet" in w.pca_view.note.text()
    menu_action(w, "Variants", "Explore variants of this grammar").trigger()  # once said "n_jobs ... False"
    assert w.last_message is None and w.progress.isVisible()
    qtbot.waitUntil(lambda: w.variants.variant_set is not None and not w.variants.busy(), timeout=60000)
    settle(qtbot, w)
    vs = w.variants.variant_set
    assert w.gallery.list.count() == 27 and len(vs.picks) == 27
    icon = w.gallery.list.item(0).icon().pixmap(100, 100).toImage()
    assert pixel_variance(icon) > 10  # a drawn plant, not a blank tile
    assert w.gallery.list.iconSize().width() >= 100  # two columns in the narrow dock, drawn at 150
    labels = [w.gallery.list.item(i).text() for i in range(27)]
    assert sum("%" in t for t in labels) >= 20  # captioned with the constants that differ
    assert not w.progress.isVisible()
    assert w.pca_view.boxes_list.count() >= 10  # one box per vocabulary qualifier
    assert w.pca_view.split.widget(0) is w.pca_view.canvas  # in the placeholder's place
    w.pca_view.set_box_checked("dense")
    assert w.pca_view.checked_boxes() == ["dense"]
    lines = [ln for ln in w.pca_view.axes.get_lines() if ln.get_color() != "black"]
    assert len(lines) == 12  # the dense box's edges
    w.open_dock("gallery")
    w.open_dock("pca")  # closed at start
    settle(qtbot, w)
    w.grab_window().save(str(artifacts / "desktop_variants.png"))
    assert "%" in w.pca_view.axes.get_xlabel()  # explained variance on the axes
    # a click on a pick's dot in the PCA cloud applies that pick
    from mpl_toolkits.mplot3d import proj3d
    from PySide6.QtCore import QPoint
    from PySide6.QtTest import QTest

    ax, canvas = w.pca_view.axes, w.pca_view.canvas
    canvas.draw()
    x, y, z = vs.picks[7]["pca"]
    px, py, _ = proj3d.proj_transform(x, y, z, ax.get_proj())
    dx, dy = ax.transData.transform((px, py))
    ratio = canvas.device_pixel_ratio
    point = QPoint(int(round(dx / ratio)), int(round(canvas.height() - dy / ratio)))
    edits = len(w.controller.explorer.session.edits)
    QTest.mouseClick(canvas, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, point)
    settle(qtbot, w)
    session = w.controller.explorer.session
    assert len(session.edits) == edits + 1 and session.edits[-1]["params"]["constants"] == {
        k: float(v) for k, v in vs.picks[7]["params"]["constants"].items()
    }


def test_gallery_click_applies_the_pick(make_window, qtbot):
    w = make_window(n=4)
    vs = explored(qtbot, w)
    item = w.gallery.list.item(5)
    rect = w.gallery.list.visualItemRect(item)
    qtbot.mouseClick(w.gallery.list.viewport(), Qt.MouseButton.LeftButton, pos=rect.center())
    settle(qtbot, w)
    edit = w.controller.explorer.session.edits[-1]
    assert edit["op"] == "regrow" and edit["params"] == {
        "rule": vs.picks[5]["params"]["rule"],
        "constants": {k: float(v) for k, v in vs.picks[5]["params"]["constants"].items()},
    }


def test_qualifier_explores_first_then_regrows_the_selection(make_window, qtbot):
    w = make_window(n=4)
    assert w.regen.qualifier.count() >= 10
    w.constants_panel.set_constant("a2", 30.0)  # the sweep must start from the session's values
    settle(qtbot, w)
    tree = w.controller.explorer.derivation.tree
    branch = int(np.flatnonzero((tree.depth == 1) & tree.alive & (tree.child_count > 0))[-1])
    chosen = tree.leaves_under(branch).tolist()  # a main branch: tips alone cannot show new constants
    w.controller.select(chosen)
    # "dense" adds segments (issue 35), which no constant of Honda does: "thick" moves its radii
    w.regen.qualifier.setCurrentIndex(w.regen.qualifier.findText("thick"))  # chosen in the list
    tip = w.regen.qualifier.itemData(w.regen.qualifier.currentIndex(), Qt.ItemDataRole.ToolTipRole)
    assert "thicker branches" in tip  # each qualifier says what it does
    with qtbot.waitSignal(w.controller.job_done, timeout=60000, check_params_cb=lambda job: job.name == "qualifier thick"):
        qtbot.mouseClick(w.regen.apply_button, Qt.MouseButton.LeftButton)
    settle(qtbot, w)
    sweep = w.variants.variant_set.exploration.sweep
    assert sweep.base_constants_["a2"] == 30.0
    session = w.controller.explorer.session
    edit = session.edits[-1]
    assert len(session.edits) == 2  # the constant, then one qualifier edit (rejected tries undone)
    assert edit["params"] is not None and edit["selection"] == sorted(chosen)
    assert w.variants.last_qualifier.roots.tolist() == [branch]  # the selection's cut, nothing more
    result = w.variants.last_qualifier
    assert result.improved and result.after.mean_radius > result.before.mean_radius
    message = w.statusBar().currentMessage()
    assert message.startswith("thick: ") and "→" in message
    assert w.regen.preview.pixmap() is not None and not w.regen.preview.pixmap().isNull()
    w.controller.undo()
    settle(qtbot, w)
    assert len(session.edits) == 1


def test_qualifier_message_names_the_metric():
    from types import SimpleNamespace

    from ramure.app.desktop.variants import qualifier_message
    from ramure.metrics.plant import PlantMetrics

    before = PlantMetrics(*[1.0] * 10)._replace(branch_density=1772.0)
    after = before._replace(branch_density=2172.4)
    result = SimpleNamespace(qualifier="dense", before=before, after=after, improved=True, tried=1, variant=3, params={"rule": 1})
    assert qualifier_message(result) == "dense: density 1772 → 2172"
    result.improved, result.tried = False, 5
    assert qualifier_message(result).startswith("dense: no variant moved")
    result.qualifier = "normal"
    assert qualifier_message(result) == "normal: applied variant 3 (rule 1) (5 tries)"


def test_cancel_stops_the_sweep(make_window, qtbot):
    w = make_window(n=8)
    w.variants.explore(n_jobs=1)
    qtbot.waitUntil(lambda: w.progress.value() >= 0, timeout=5000)
    w.cancel_button.click()
    # the worker stops first; its "cancelled" signal (which hides the bar) arrives an event later
    qtbot.waitUntil(lambda: not w.variants.busy() and not w.progress.isVisible(), timeout=60000)
    assert w.variants.variant_set is None and not w.cancel_button.isVisible()
    assert w.gallery.list.count() == 0


def test_open_exploration_folder(make_window, qtbot, tmp_path):
    from ramure.metrics import explore, write_exploration

    write_exploration(explore(ROOT / "grammars" / "honda_sympodial.lsys", n=4, n_jobs=1), tmp_path / "exp")
    w = make_window(n=4)
    vs = w.variants.open_exploration(tmp_path / "exp")
    qtbot.waitUntil(lambda: not w.variants.busy(), timeout=30000)
    assert w.gallery.list.count() == 27 and vs.points.shape[1] == 3
    assert w.variants.open_exploration(tmp_path / "missing") is None and "picks.json" in w.last_message


def test_volumetric_fruit_can_be_picked(make_window, qtbot):
    if not w_fruit_available():
        pytest.skip("gmap volumetric fruit not available")
    w = make_window(ROOT / "grammars" / "fruit_tree.lsys", n=4)
    w.fruit_action.setChecked(True)
    qtbot.waitUntil(lambda: w.view.fruit is not None, timeout=30000)
    settle(qtbot, w)
    fruit = w.view.fruit
    leaves = np.asarray(fruit.cell_data["leaf_id"])
    target = int(leaves[0])
    centre = np.asarray(fruit.extract_cells(np.flatnonzero(leaves == target)).center)
    w.view.click_at(*w.view.project(centre[None])[0])
    assert w.controller.explorer.selection == [target]
    rgb = np.asarray(w.view.fruit.cell_data["rgb"])
    assert (rgb[leaves == target] == FRUIT_SELECTED).all()  # blue: red on orange reads as ripe
    w.fruit_action.setChecked(False)
    assert w.view.fruit is None


def w_fruit_available():
    from ramure.app.desktop.panels.variants import fruit_available

    return fruit_available()


def fruit_sphere_area(mesh):
    kind = np.asarray(mesh.cell_data["kind"])
    return float(mesh.extract_cells(np.flatnonzero(kind == 2)).compute_cell_sizes().cell_data["Area"].sum())


def test_volumes_hide_the_fruit_spheres_and_regrow_fruit_with_a_preset(make_window, qtbot, artifacts):
    if not w_fruit_available():
        pytest.skip("gmap volumetric fruit not available")
    w = make_window(ROOT / "grammars" / "fruit_tree.lsys", n=4)
    snap = w.controller.snapshot
    full = fruit_sphere_area(snap.mesh)
    assert full > 0 and fruit_sphere_area(w.view.mesh) == pytest.approx(full)
    assert w.regen.fruit_box.isVisibleTo(w.regen) and not w.regen.regrow_fruit_button.isEnabled()
    branch = int(snap.segment_leaf[0])
    w.controller.select([branch])
    assert not w.regen.regrow_fruit_button.isEnabled()  # a branch is no fruit

    fruit = w.presenter.fruit_leaves.tolist()
    w.controller.select(fruit[:2])
    assert w.regen.regrow_fruit_button.isEnabled() and "2 of" in w.regen.fruit_note.text()
    w.regen.fruit_preset.setCurrentIndex(w.regen.fruit_preset.findData("pear"))
    with qtbot.waitSignal(w.controller.job_done, timeout=30000, check_params_cb=lambda job: job.name == "regrow fruit"):
        qtbot.mouseClick(w.regen.regrow_fruit_button, Qt.MouseButton.LeftButton)
    assert w.fruit_action.isChecked()  # regrowing fruit shows the volumes
    qtbot.waitUntil(lambda: w.view.fruit is not None, timeout=30000)
    settle(qtbot, w)
    session = w.controller.explorer.session
    assert session.edits[-1]["op"] == "fruit"
    overrides = session.fruit_overrides()
    assert {overrides[leaf]["preset"] for leaf in fruit[:2]} == {"pear"} and fruit[2] not in overrides
    assert fruit_sphere_area(w.view.mesh) == 0  # spheres shrunk away under the volumes
    assert fruit_sphere_area(w.controller.snapshot.mesh) == pytest.approx(full)  # the model's mesh kept
    w.grab_window().save(str(artifacts / "desktop_fruit_volumes.png"))
    w.fruit_action.setChecked(False)
    assert fruit_sphere_area(w.view.mesh) == pytest.approx(full)


def test_a_rectangle_selects_fruit_and_they_turn_blue(make_window, qtbot):
    from PySide6.QtTest import QTest

    w = make_window(ROOT / "grammars" / "fruit_tree.lsys", n=4)
    total = len(w.presenter.fruit_leaves)
    assert total > 0
    size = w.view.plotter.size()
    QTest.mousePress(
        w.view.plotter, Qt.MouseButton.RightButton, Qt.KeyboardModifier.NoModifier, w.view.plotter.rect().topLeft() + QPoint(2, 2)
    )
    QTest.mouseMove(w.view.plotter, QPoint(size.width() - 3, size.height() - 3))
    QTest.mouseRelease(
        w.view.plotter, Qt.MouseButton.RightButton, Qt.KeyboardModifier.NoModifier, QPoint(size.width() - 3, size.height() - 3)
    )
    settle(qtbot, w)
    selected = set(w.controller.explorer.selection)
    assert set(w.presenter.fruit_leaves.tolist()) <= selected  # every fruit, not 0 of 20
    assert f"{total} of {total} fruit selected" in w.regen.fruit_note.text()
    mesh = w.view.mesh
    fruit = np.asarray(mesh.cell_data["kind"]) == 2
    assert (np.asarray(mesh.cell_data["rgb"])[fruit] == FRUIT_SELECTED).all()


def test_cut_fruit_open_shows_their_inside(make_window, qtbot, artifacts):
    w = make_window(ROOT / "grammars" / "fruit_tree.lsys", n=4)
    w.variants.cut_toggle.trigger()  # View > Cut fruit open (turns the volumes on)
    qtbot.waitUntil(lambda: w.view.fruit is not None and w.variants.fruit_job_cut, timeout=30000)
    settle(qtbot, w)
    cut = w.view.fruit
    whole = w.controller.read(lambda ex: ex.fruit_surface(), wait=None)
    assert set(np.unique(cut.cell_data["leaf_id"])) == set(np.unique(whole.cell_data["leaf_id"]))  # every fruit
    camera = w.view.plotter.camera
    toward = np.subtract(camera.position, camera.focal_point)
    from ramure.gmap.kernel.pyvista import boundary_polydata

    # the cut fruit are subdivided once (every tissue shows): compare with the same fruit whole
    fine = w.controller.read(lambda ex: boundary_polydata(ex.fruit_volumes(volume_levels=1)), wait=None)
    assert (
        np.asarray(cut.bounds).reshape(3, 2)[:, 1] @ np.abs(toward)
        <= np.asarray(fine.bounds).reshape(3, 2)[:, 1] @ np.abs(toward) + 1e-9
    )
    assert len(np.unique(cut.cell_data["tissue"])) > 1  # inner tissues exposed
    w.view.reset_camera()
    settle(qtbot, w)
    w.view.grab_image().save(str(artifacts / "desktop_fruit_cut.png"))
    w.variants.cut_toggle.trigger()
    qtbot.waitUntil(lambda: w.view.fruit is not None and w.view.fruit.n_cells == whole.n_cells, timeout=30000)


@pytest.mark.parametrize(
    "doc, words",
    [({"seed": "abc"}, "'seed' must be an integer, not 'abc'"), ({"n": [3]}, "'n' must be an integer"), ([], "JSON object")],
)
def test_open_exploration_refuses_pca_json_values_of_the_wrong_type(make_window, tmp_path, doc, words):
    import json

    from ramure.studies import lattice_picks

    picks = [dict(id=p.id, variant=p.variant, pca=list(p.pca), params=p.params) for p in lattice_picks()]
    (tmp_path / "picks.json").write_text(json.dumps(picks))
    (tmp_path / "pca.json").write_text(json.dumps(doc))
    w = make_window(n=2)
    assert w.variants.open_exploration(tmp_path) is None and words in w.last_message
    assert w.variants.variant_set is None
    (tmp_path / "pca.json").write_text(json.dumps({"grammar": "mine", "n": 3, "seed": 2}))
    vs = w.variants.open_exploration(tmp_path)
    assert (vs.name, vs.n, vs.seed, vs.points) == ("mine", 3, 2, None)


def test_the_qualifier_box_takes_the_words_people_type(make_window, qtbot):
    """Issue 35, 'the words people type': comparatives, synonyms and French are typed in the
    box (with suggestions) and reach the model, which reads them all."""
    from PySide6.QtTest import QTest

    from ramure.metrics.qualifiers import canonical_name

    w = make_window(n=3)
    box = w.regen.qualifier
    assert box.isEditable()
    offered = set(box.completer().model().stringList())
    assert {"taller", "denser", "touffu", "haut"} <= offered  # "plus touffu" is read, not listed
    box.lineEdit().clear()
    with qtbot.waitSignal(w.regen.qualifier_chosen, timeout=5000) as chosen:
        QTest.keyClicks(box.lineEdit(), "plus touffu")
        QTest.keyClick(box.lineEdit(), Qt.Key.Key_Return)
    assert chosen.args == ["plus touffu"] and canonical_name("plus touffu") == "bushy"
    with qtbot.waitSignal(w.regen.apply_qualifier, timeout=5000) as applied:
        w.regen.apply_button.clicked.disconnect()  # the signal alone: no exploration in this test
        w.regen.apply_button.clicked.connect(lambda: w.regen.apply_qualifier.emit(box.currentText()))
        qtbot.mouseClick(w.regen.apply_button, Qt.MouseButton.LeftButton)
    assert applied.args == ["plus touffu"]


def test_variants_dock_offers_hidden_constants_and_wide_steps(make_window, qtbot, monkeypatch):
    """The dock's boxes reach the sweep as the CLI's --hidden --wide 0.25 (issue 35); both off by
    default, so the default cloud (and its count, 486 on Honda n=4) stays the thesis's."""
    from ramure.app.desktop import variants as desktop_variants
    from ramure.errors import RamureError

    asked = []

    def explore_plant(ls, n, seed, **kwargs):
        asked.append({k: kwargs[k] for k in ("hidden", "wide")})
        raise RamureError("enough: the options were read")

    monkeypatch.setattr(desktop_variants, "explore_plant", explore_plant)
    w = make_window(n=4)
    gallery = w.variants.gallery
    assert not gallery.hidden_box.isChecked() and gallery.wide_box.value() == 0.0
    assert gallery.wide_box.text() == "no wide step" and gallery.hidden_box.isVisibleTo(w)
    for hidden, wide in ((False, 0.0), (True, 0.25)):
        gallery.hidden_box.setChecked(hidden)
        gallery.wide_box.setValue(wide)
        w.variants.explore(n_jobs=1)
        qtbot.waitUntil(lambda: not w.variants.busy(), timeout=20000)
    assert asked == [{"hidden": False, "wide": None}, {"hidden": True, "wide": 0.25}]
    assert w.variants.variant_set is None  # the refusal was reported, nothing shown
