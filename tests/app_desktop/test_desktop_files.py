"""File menu: grammars, sessions, exports, screenshots, recent files, unsaved changes."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv

from ramure.app.desktop.view.thumbnails import pixel_variance
from desktop_helpers import ROOT, settle

pytestmark = pytest.mark.gui


def test_session_round_trip(make_window, qtbot, tmp_path):
    w = make_window(ROOT / "grammars" / "stochastic_plant.lsys", n=4)
    ex = w.controller.explorer
    snap = w.controller.snapshot
    before = ex.derivation.to_string()
    order = np.asarray(snap.skeleton.order)
    w.controller.select(snap.segment_leaf[np.flatnonzero(order == order.max())[:6]])
    w.controller.regrow()
    settle(qtbot, w)
    grown = ex.derivation.to_string()
    assert grown != before
    path = w.files.save_session(tmp_path / "s.json")
    assert path.is_file() and not w.dirty
    w.controller.undo()
    settle(qtbot, w)
    assert ex.derivation.to_string() != grown
    w.files.load_session(path)
    settle(qtbot, w)
    assert ex.derivation.to_string() == grown
    assert w.editor.text() == ex.document_text()  # the text with the session's n: 4 written in
    assert str(path.resolve()) in w.files.recent()


def test_a_corrupt_session_is_refused(make_window, qtbot, tmp_path):
    w = make_window()
    version = w.presenter.drawn_version
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "ramure-session", "version": 1, "grammar": "n: 1\\nw: F"')
    w.files.load_session(bad)
    settle(qtbot, w)
    assert "JSON" in w.last_message and w.presenter.drawn_version == version


def test_open_and_save_grammar(make_window, qtbot, tmp_path):
    w = make_window()
    w.files.open_grammar(ROOT / "grammars" / "fruit_tree.lsys")
    settle(qtbot, w)
    assert "Fruit" in w.editor.text() and w.controller.explorer.path.name == "fruit_tree.lsys"
    assert "fs" in w.constants_panel.rows  # the panel was rebuilt from the new #defines
    kinds = np.asarray(w.view.mesh.cell_data["kind"])
    assert (kinds == 2).any()  # fruit are drawn
    w.editor.edit.setPlainText(w.editor.text().replace("#define a 40", "#define a 30"))
    qtbot.waitUntil(lambda: w.controller.explorer.constants.get("a") == 30, timeout=5000)
    settle(qtbot, w)
    assert w.dirty
    out = w.files.save_grammar(tmp_path / "mine.lsys")
    assert "#define a 30" in out.read_text() and not w.dirty
    w.files.open_grammar(tmp_path / "missing.lsys")
    assert "no such" in w.last_message


def test_exports_and_screenshot(make_window, qtbot, tmp_path):
    w = make_window()
    cells = w.controller.snapshot.mesh.n_cells
    vtp = w.files.export_mesh(tmp_path / "plant.vtp")
    assert pv.read(vtp).n_cells == cells
    obj = w.files.export_mesh(tmp_path / "plant.obj")
    assert obj.read_text().count("\nf ") > 0
    gltf = w.files.export_mesh(tmp_path / "plant.gltf")
    assert gltf.stat().st_size > 1000
    assert w.files.export_mesh(tmp_path / "plant.xyz") is None and "cannot export" in w.last_message
    png = w.files.screenshot(tmp_path / "view.png")
    from PySide6.QtGui import QImage

    assert pixel_variance(QImage(str(png))) > 20


def test_unsaved_changes_prompt(make_window, qtbot, monkeypatch):
    from PySide6.QtWidgets import QMessageBox

    w = make_window()
    w.ask = True
    w.constants_panel.set_constant("a2", 30.0)
    settle(qtbot, w)
    assert w.dirty and w.windowTitle().startswith("honda_sympodial.lsys *")
    asked = []
    monkeypatch.setattr(QMessageBox, "question", lambda *a, **k: asked.append(a) or QMessageBox.StandardButton.Cancel)
    assert not w.confirm_discard() and asked
    assert w.files.open_grammar(ROOT / "grammars" / "algae.lsys") is None  # cancelled: nothing opened
    monkeypatch.setattr(QMessageBox, "question", lambda *a, **k: QMessageBox.StandardButton.Discard)
    assert w.confirm_discard()
    w.ask = False


def test_obj_export_has_groups_materials_normals_volumetric_fruit_and_y_up(make_window, qtbot, tmp_path):
    w = make_window(ROOT / "grammars" / "fruit_tree.lsys", n=4)
    w.fruit_action.setChecked(True)  # volumetric fruit on screen: the export carries them
    qtbot.waitUntil(lambda: w.view.fruit is not None, timeout=30000)
    settle(qtbot, w)
    w.yup_action.trigger()  # File > Export with Y up
    assert w.yup_action.isChecked()
    obj = w.files.export_mesh(tmp_path / "plant.obj")
    text = obj.read_text()
    lines = text.splitlines()
    (mtl,) = tmp_path.glob("plant.*.mtl")
    assert f"mtllib {mtl.name}" in text
    # bark, leaf and one material per fruit tissue in the species' colours (fruit_exocarp, ...)
    materials = [ln.split()[1] for ln in mtl.read_text().splitlines() if ln.startswith("newmtl ")]
    tissues = np.unique(np.asarray(w.view.fruit.cell_data["tissue"]))
    assert materials[:2] == ["bark", "leaves"] and len(materials) == 2 + len(tissues)
    assert all(name.startswith("fruit_") for name in materials[2:])
    groups = [ln.split()[1] for ln in lines if ln.startswith("g ")]
    assert groups[0] == "bark" and groups[-1] == "fruit"
    vertices = np.array([[float(v) for v in ln.split()[1:]] for ln in lines if ln.startswith("v ")])
    normals = np.array([[float(v) for v in ln.split()[1:]] for ln in lines if ln.startswith("vn ")])
    assert len(normals) == len(vertices) and np.allclose(np.linalg.norm(normals, axis=1), 1, atol=1e-2)
    start = lines.index("g fruit")
    fruit_vertices = sum(1 for ln in lines[start:] if ln.startswith("v "))
    # the volumes' surface, not the spheres: each tissue's part holds the points its faces use
    surface = w.view.fruit.extract_surface(algorithm="dataset_surface")
    tissue = np.asarray(surface.cell_data["tissue"])
    assert fruit_vertices == sum(surface.extract_cells(np.flatnonzero(tissue == t)).n_points for t in tissues)
    bounds = np.asarray(w.view.mesh.bounds).reshape(3, 2)
    height = bounds[2, 1] - bounds[2, 0]
    assert abs((vertices[:, 1].max() - vertices[:, 1].min()) - height) < 0.05 * height + 1e-6  # Y up
    assert " " in lines[-1] and lines[-1].startswith("f ") and "//" in lines[-1]


def test_screenshot_goes_through_a_temporary_file(make_window, tmp_path, monkeypatch):
    """Issue 37: the screenshot was saved straight onto its file, so a kill mid-write left half
    a picture; now it is written beside it and renamed.  What a killed screenshot left (a
    temporary file of a dead process) is removed by the next one; a full disk keeps the old."""
    import errno
    import os
    import subprocess
    import sys

    w = make_window()
    png = w.files.screenshot(tmp_path / "view.png")
    old = png.read_bytes()
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    stale = tmp_path / f".view.png.{int(dead.stdout)}.abcd1234.tmp.png"
    stale.write_bytes(old[:100])
    assert w.files.screenshot(png) == png and not stale.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["view.png"]
    old = png.read_bytes()

    def no_space(*_args):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "fsync", no_space)
    assert w.files.screenshot(png) is None and "No space left on device" in w.last_message
    assert png.read_bytes() == old and sorted(p.name for p in tmp_path.iterdir()) == ["view.png"]


def test_loading_a_session_shows_its_replay_in_the_status_bar(make_window, qtbot, tmp_path):
    """Issue 37: a session of many edits replayed with no word; the status bar follows it."""
    from ramure.lsys import LSystem
    from ramure.lsys.regeneration.regen import Session

    session = Session(LSystem.from_file(ROOT / "grammars" / "stochastic_plant.lsys"), n=4, seed=1)
    for _ in range(3):
        session.regrow([int(session.tree.leaves[-1])], rho=0.5)
    path = session.save(tmp_path / "s.json")
    w = make_window()
    shown = []
    w.statusBar().messageChanged.connect(shown.append)
    w.files.load_session(path)
    settle(qtbot, w)
    replay = [m for m in shown if m.startswith("Replaying")]
    assert replay == [f"Replaying the session: edit {i} of 3" for i in (1, 2, 3)]
    assert len(w.controller.explorer.session.edits) == 3
