"""The desktop Wood dock, driven without the main window (a stub controller, off-screen plotter)."""

import os

import numpy as np
import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("PySide6")


class _Plotter:
    """Records what the dock asks of a plotter (the real one is a pyvistaqt QtInteractor)."""

    def __init__(self, parent):
        from PySide6.QtWidgets import QWidget

        self.interactor = QWidget(parent)
        self.clipped = []
        self.meshes = []

    def clear(self):
        self.clipped.clear()

    def add_mesh_clip_plane(self, grid, **kwargs):
        self.clipped.append((grid, kwargs))

    def view_isometric(self):
        pass

    def reset_camera(self):
        pass

    # the plank, shown face-on
    window_size = (800, 600)

    def add_mesh(self, mesh, **kwargs):
        self.meshes.append((mesh, kwargs))

    def enable_parallel_projection(self):
        self.parallel = True

    def disable_parallel_projection(self):
        self.parallel = False

    def reset_camera_clipping_range(self):
        pass

    meshes: list = []
    parallel = False
    camera_position = None

    class camera:  # noqa: N801 - stands for the plotter's camera object
        parallel_scale = 1.0


class _Controller:
    def __init__(self, derivation):
        from PySide6.QtCore import QObject, Signal

        class Signals(QObject):
            selection_changed = Signal(tuple)

        self.signals = Signals()
        self.selection_changed = self.signals.selection_changed
        self.derivation = derivation

    def read(self, fn, wait=0.0):
        class Ex:
            pass

        ex = Ex()
        ex.derivation, ex.skeleton = self.derivation, self.derivation.skeleton()
        return fn(ex)


@pytest.fixture(scope="module")
def app():
    from PySide6.QtWidgets import QApplication

    return QApplication.instance() or QApplication([])


def test_grow_from_the_plant_and_highlight_a_knot(app):
    from ramure.app.desktop.panels.wood import SELECTED_RGB, WoodPanel
    from ramure.lsys import LSystem

    d = LSystem.from_file("abop_tree").derive(n=5)
    panel = WoodPanel(_Controller(d), plotter_factory=_Plotter)
    panel.years.setValue(5)
    panel.from_plant.setChecked(True)
    wood = panel.grow()
    assert wood is not None and wood.branches and "knot" in panel.facts.text()
    assert f"knots: {len(wood.branch_axis)} live, 0 dead" in panel.facts.text()  # a plant's branches live
    assert "(by order 1: 3, 2: 2, 3: 1); left out: 7 last year, 1 beyond stub" in panel.facts.text()
    grid, kwargs = panel.plotter.clipped[-1]
    assert kwargs["normal"] == "z" and np.array_equal(np.unique(grid.cell_data["volume"]), np.arange(wood.gm.n_volumes))
    leaf = panel.branch_leaves[0][0]
    panel.controller.selection_changed.emit((leaf,))
    rgb = np.asarray(panel.plotter.clipped[-1][0].cell_data["rgb"])
    knot = np.asarray(grid.cell_data["axis"]) == 1
    assert np.all(rgb[knot] == SELECTED_RGB) and not np.any(np.all(rgb[~knot] == SELECTED_RGB, axis=1))


def test_refusal_is_shown_in_the_dock(app):
    from ramure.app.desktop.panels.wood import WoodPanel

    panel = WoodPanel(None, plotter_factory=_Plotter)
    panel.species.addItem("baobab")
    panel.species.setCurrentText("baobab")
    assert panel.grow() is None and "Refused" in panel.facts.text()


def test_clicking_a_branch_of_the_real_plant_paints_its_knot(app):
    """The real controller and explorer: a click on a mesh cell of a branch (pick_cell) selects its
    history leaf, and the dock paints that branch's knot, and only it."""
    from ramure.app.desktop.controller import Controller
    from ramure.app.desktop.panels.wood import SELECTED_RGB, WoodPanel
    from ramure.app.model import Explorer
    from ramure.grammars import path

    controller = Controller(Explorer(str(path("abop_tree")), n=5))
    panel = WoodPanel(controller, plotter_factory=_Plotter)
    panel.years.setValue(5)
    panel.from_plant.setChecked(True)
    wood = panel.grow()
    assert wood is not None and len(panel.branch_leaves) >= 2
    cell_leaf = controller.read(lambda ex: np.asarray(ex.mesh.cell_data["leaf_id"]).copy(), wait=None)
    b = 1  # the second branch: knot axis 2
    cell = int(np.flatnonzero(np.isin(cell_leaf, panel.branch_leaves[b]))[0])
    controller.pick_cell(cell)  # what a left click on the plant does
    grid = panel.plotter.clipped[-1][0]
    rgb = np.asarray(grid.cell_data["rgb"])
    painted = np.all(rgb == SELECTED_RGB, axis=1)
    knot = np.asarray(grid.cell_data["axis"]) == b + 1
    assert knot.any() and np.all(painted[knot]) and not np.any(painted[~knot])


def test_plank_controls_saw_a_preset_board_that_fills_the_view(app):
    # the dock had no plank control: planks existed only in ramure wood
    from PySide6.QtCore import Qt
    from PySide6.QtTest import QTest

    from ramure.app.desktop.panels.wood import WoodPanel
    from ramure.gmap.organs import wood as W

    panel = WoodPanel(None, plotter_factory=_Plotter)
    panel.years.setValue(4)
    assert panel.grow() is not None
    trunk_wood = (np.asarray(panel.grid.cell_data["axis"]) == 0) & (np.asarray(panel.grid.cell_data["wood"]) != W.CODES["bark"])
    centres = np.asarray(panel.grid.cell_centers().points)[trunk_wood]
    radius = np.hypot(centres[:, 0], centres[:, 1]).max()
    panel.plank_preset.setFocus()
    QTest.keyClick(panel.plank_preset, Qt.Key.Key_Down)  # flat-sawn -> quarter-sawn
    assert panel.plank_preset.currentText() == "quarter-sawn"
    assert panel.plank_offset.value() == pytest.approx(-10.0)  # centred on the pith: -thickness / 2
    QTest.keyClick(panel.plank_preset, Qt.Key.Key_Down)  # -> rift
    assert panel.plank_offset.value() == pytest.approx(1000 * 0.3 * radius, abs=0.05)
    panel.plank_direction.selectAll()
    QTest.keyClicks(panel.plank_direction, "90")  # a board facing +y
    QTest.mouseClick(panel.plank_button, Qt.MouseButton.LeftButton)
    plotter = panel.plotter
    named = {kw.get("name"): (m, kw) for m, kw in plotter.meshes}
    mesh, kwargs = named["plank"]
    texture = named["texture"][0]  # the species' pores and rays, one point a pixel, on the face
    assert texture.n_points > 1000 and np.ptp(np.asarray(texture.point_data["rgb"]), axis=0).max() > 0
    along_normal = np.asarray(mesh.points)[:, 1]
    offset = panel.plank_offset.value() / 1000  # the spin box shows tenths of a millimetre
    assert along_normal.min() >= offset - 1e-9 and along_normal.max() <= offset + 0.02 + 1e-9  # the slab asked for
    assert plotter.parallel and not kwargs["lighting"] and "rings" in panel.facts.text()
    assert " live, " in panel.facts.text() and " dead)" in panel.facts.text()  # the plank's knots, by state
    position, focal, up = (np.asarray(v) for v in plotter.camera_position)
    assert np.allclose(up, [1, 0, 0], atol=1e-9) and (position - focal)[1] < 0  # face-on, from the pith's side
    length = np.ptp(np.asarray(mesh.points)[:, 2])
    width = np.ptp(np.asarray(mesh.points) @ up)
    scale = plotter.camera.parallel_scale
    fill = max(length / (2 * scale * 800 / 600), width / (2 * scale))
    assert 0.9 < fill <= 1.0  # the cut face fills the view
    panel.plank_offset.setValue(2000.0)
    QTest.mouseClick(panel.plank_button, Qt.MouseButton.LeftButton)
    assert "Refused" in panel.facts.text() and "misses" in panel.facts.text() and len(plotter.meshes) == 2


class _TallPlotter(_Plotter):
    window_size = (300, 600)  # a dock's view: taller than wide


def test_a_tall_dock_shows_the_board_upright_and_filling_it(app):
    """In a view taller than wide the board is drawn as the tree stood, the trunk axis up, so it
    fills the view's height instead of lying across its width (it filled a third of a 276 x 503
    dock)."""
    from PySide6.QtCore import Qt
    from PySide6.QtTest import QTest

    from ramure.app.desktop.panels.wood import WoodPanel

    panel = WoodPanel(None, plotter_factory=_TallPlotter)
    panel.years.setValue(4)
    assert panel.grow() is not None
    QTest.mouseClick(panel.plank_button, Qt.MouseButton.LeftButton)
    plotter = panel.plotter
    mesh = {kw.get("name"): m for m, kw in plotter.meshes}["plank"]
    position, focal, up = (np.asarray(v) for v in plotter.camera_position)
    assert np.allclose(up, [0, 0, 1], atol=1e-9)  # the trunk axis up
    pts = np.asarray(mesh.points)
    right = np.cross(focal - position, up)
    right /= np.linalg.norm(right)
    length, width = np.ptp(pts[:, 2]), np.ptp(pts @ right)
    scale = plotter.camera.parallel_scale
    fill = max(length / (2 * scale), width / (2 * scale * 300 / 600))
    assert 0.9 < fill <= 1.0 and length / (2 * scale) > 0.9  # the board's length fills the height
