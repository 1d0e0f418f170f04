"""The 3D view: backend choice, colours, camera and the static fallback (trame itself is not installed here)."""

from __future__ import annotations

import numpy as np
import pytest

from ramure.app.jupyter import NotebookExplorer
from ramure.app.jupyter import view as view_module
from ramure.app.jupyter.view import CUT, cut_leaves, resolve_backend, view_colors
from ramure.app.render import BARK
from jupyter_helpers import HONDA
from ramure.errors import ValueRefused


def test_backend_resolution(monkeypatch):
    assert resolve_backend("static") == "static"
    assert resolve_backend("auto") == "static"  # no kernel here
    with pytest.raises(ValueRefused, match="view backend"):
        resolve_backend("opengl")
    monkeypatch.setattr(view_module, "trame_available", lambda: True)
    monkeypatch.setattr(view_module, "in_kernel", lambda: True)
    assert resolve_backend("auto") == "server"  # trame, server rendering: picking works
    assert resolve_backend("client") == "client"
    import pyvista as pv

    monkeypatch.setattr(pv.global_theme, "jupyter_backend", "static")
    assert resolve_backend("auto") == "static"
    monkeypatch.setattr(view_module, "trame_available", lambda: False)
    assert resolve_backend("trame") == "static"


def test_trame_failure_falls_back_to_the_picture(monkeypatch):
    import ipywidgets as W

    class Broken:
        def __init__(self, *a, **k):
            raise RuntimeError("no server")

    monkeypatch.setattr(view_module, "resolve_backend", lambda backend: "server")
    monkeypatch.setattr(view_module, "TrameView", Broken)
    ex = NotebookExplorer(HONDA, n=3, size=(100, 100))
    assert ex.view.backend == "static" and isinstance(ex.view.widget, W.Image)
    assert not ex.view.picking and ex.view.image.value[:4] == b"\x89PNG"
    assert "interactive view unavailable (RuntimeError: no server)" in ex.message.text


def test_colours_selection_kinship_and_cut(explorer):
    ex = explorer
    mesh = ex.model.mesh
    bark = (np.array(BARK) * 255).astype(np.uint8)
    assert (view_colors(ex.model) == bark).all()
    leaf = int(mesh.cell_data["leaf_id"][np.flatnonzero(np.asarray(mesh.cell_data["order"]) == 3)[0]])
    ex.select([leaf])
    rgb = view_colors(ex.model)
    mine = np.asarray(mesh.cell_data["leaf_id"]) == leaf
    assert (rgb[mine] == (255, 0, 0)).all()
    hues = {tuple(c) for c in rgb[~mine].tolist()}
    assert len(hues) >= 3 and tuple(bark.tolist()) not in hues  # kinship hues, red to blue
    ex.select(ex.model.session.leaves_with_symbol("F")[-2:].tolist())
    ex.set_rho(5)  # a low ρ climbs above the selection: the cut takes unselected branches too
    assert set(ex.selection) <= set(cut_leaves(ex.model).tolist())
    rgb = view_colors(ex.model, show_cut=True)
    orange = np.all(rgb == (np.array(CUT) * 255).astype(np.uint8), axis=1)
    selected = np.isin(mesh.cell_data["leaf_id"], ex.selection)
    assert orange.any() and not np.any(orange & selected) and (rgb[selected] == (255, 0, 0)).all()


def test_camera_and_cut_preview_rerender(explorer):
    ex = explorer
    front = ex.png()
    ex.camera.value = "top"
    assert ex.view.view == "top" and ex.view.image.value != front
    before = ex.view.image.value
    ex.select_where(min_order=4)
    ex.show_cut.value = True
    assert ex.view.show_cut and ex.view.image.value != before
    ex.set_view("sideways")
    assert ex.message.kind == "error"


@pytest.mark.slow
def test_trame_view_picks_in_a_kernel():
    """Only where pyvista's trame backend is installed: the interactive view starts in a
    kernel and a click on a branch selects its leaf."""
    pytest.importorskip("trame_pyvista")
    nbformat = pytest.importorskip("nbformat")
    from jupyter_helpers import execute

    code = f"""from ramure.app.jupyter import NotebookExplorer
ex = NotebookExplorer({HONDA!r}, n=5)
pl, sk = ex.view.trame.plotter, ex.skeleton
k = int(np.argmax(sk.order))
pl.renderer.SetWorldPoint(*((sk.start[k] + sk.end[k]) / 2), 1.0)
pl.renderer.WorldToDisplay()
x, y, _ = pl.renderer.GetDisplayPoint()
pl.render()
pl.iren._mouse_left_button_click(int(round(x)), int(round(y)))
print(ex.view.backend, ex.view.picking, ex.selection == [int(sk.leaf_id[k])])"""
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("import numpy as np\n" + code)])
    execute(nb, {"PYVISTA_JUPYTER_BACKEND": "trame"}, timeout=120)
    out = "".join(o.get("text", "") for o in nb.cells[0].outputs if o.output_type == "stream")
    assert "server True True" in out, out


@pytest.mark.parametrize("side", ["iso", "front", "top"])
def test_the_plant_fills_and_centres_the_picture(side):
    import io

    from matplotlib.image import imread

    ex = NotebookExplorer(HONDA, n=6, view="static", size=(160, 160))
    ex.set_view(side)
    rgb = imread(io.BytesIO(ex.png()), format="png")[..., :3]
    rows, cols = np.nonzero(np.any(rgb < 0.9, axis=2))  # not the white background
    height, width = np.ptp(rows) + 1, np.ptp(cols) + 1
    assert max(height, width) >= 0.8 * 160 and max(height, width) <= 0.97 * 160  # fills, not cropped
    assert abs((rows.min() + rows.max()) / 2 - 80) < 10 and abs((cols.min() + cols.max()) / 2 - 80) < 10


def test_fruit_are_orange_so_red_means_selected():
    from jupyter_helpers import ROOT, red_pixels

    ex = NotebookExplorer(str(ROOT / "grammars" / "fruit_tree.lsys"), view="static", size=(200, 200))
    assert red_pixels(ex.png()) == 0
    ex.select(ex.model.fruit_ids()[:4])
    assert red_pixels(ex.png()) > 0


@pytest.mark.parametrize("side", ["top", "iso"])
def test_the_trame_view_frames_the_plant_below_its_toolbar(side):
    """pyvista's trame menu floats over the view's top (20 px down, 36 px tall): the view is
    ``TOOLBAR_BAND`` taller than the explorer's size and the plant is framed below that band."""
    import io

    from matplotlib.image import imread

    from ramure.app.jupyter.view import TOOLBAR_BAND, _screenshot, fit_view, trame_window
    from ramure.app.render import frame_camera

    assert TOOLBAR_BAND >= 20 + 36 and trame_window((160, 160)) == (160, 160 + TOOLBAR_BAND)
    mesh = NotebookExplorer(HONDA, n=6, view="static").model.mesh
    width, height = trame_window((160, 160))

    def draw(plotter):
        plotter.add_mesh(mesh, color="green")
        frame_camera(plotter, mesh.bounds, side)
        fit_view(plotter, mesh.points, 0.9, top=TOOLBAR_BAND / height)

    rgb = imread(io.BytesIO(_screenshot((width, height), draw)), format="png")[..., :3]
    rows, cols = np.nonzero(np.any(rgb < 0.9, axis=2))
    assert rows.min() >= TOOLBAR_BAND  # nothing under the menu
    assert max(np.ptp(rows) + 1, np.ptp(cols) + 1) >= 0.8 * 160  # still fills the picture below it
    assert abs((rows.min() + rows.max()) / 2 - (TOOLBAR_BAND + 80)) < 10 and abs((cols.min() + cols.max()) / 2 - 80) < 10


def test_rectangle_mode_selects_what_a_drag_encloses_in_a_kernel():
    """Only where pyvista's trame backend is installed: with ▭ rectangle on, a left drag in the
    interactive view (the browser's mouse events, handed to VTK as trame's mouse handler hands
    them) draws a band and selects the leaves the model finds inside, the camera staying still;
    a press and release in place picks like a click; with the button off a drag turns the view."""
    pytest.importorskip("trame_pyvista")
    nbformat = pytest.importorskip("nbformat")
    from jupyter_helpers import execute

    code = f"""from ramure.app.jupyter import NotebookExplorer
from vtkmodules.vtkWebCore import vtkWebApplication, vtkWebInteractionEvent
ex = NotebookExplorer({HONDA!r}, n=6)
pl = ex.view.trame.plotter
camera = pl.camera_position
web, L = vtkWebApplication(), vtkWebInteractionEvent.LEFT_BUTTON
def mouse(buttons, x, y):  # trame's viewport.mouse.interaction: x, y as fractions of the view
    event = vtkWebInteractionEvent()
    event.SetButtons(buttons)
    event.SetX(x)
    event.SetY(y)
    web.HandleInteractionEvent(pl.render_window, event)
ex.rectangle.value = True  # the button
mouse(L, 0.25, 0.25); mouse(L, 0.5, 0.5)
band = ex.view.trame.rectangle.band.GetVisibility()
mouse(L, 0.75, 0.75); mouse(0, 0.75, 0.75)
w, h = pl.window_size
expected = ex.model.leaves_in_view(*ex.view.trame.camera(), (w / 4, h / 4, 3 * w / 4, 3 * h / 4))
print("band", band, ex.view.trame.rectangle.band.GetVisibility())
print("selected", len(ex.selection), len(set(ex.skeleton.leaf_id.tolist())), ex.selection == expected)
print("still", pl.camera_position == camera)
print("message", ex.message.text)
sk = ex.skeleton
k = int(np.argmax(sk.order))
pl.renderer.SetWorldPoint(*((sk.start[k] + sk.end[k]) / 2), 1.0)
pl.renderer.WorldToDisplay()
x, y, _ = pl.renderer.GetDisplayPoint()
mouse(L, x / w, y / h); mouse(0, x / w, y / h)
print("click", ex.selection == [int(sk.leaf_id[k])])
ex.rectangle.value = False
mouse(L, 0.25, 0.25); mouse(L, 0.5, 0.4); mouse(0, 0.5, 0.4)
print("turned", pl.camera_position != camera, ex.selection == [int(sk.leaf_id[k])])"""
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("import numpy as np\n" + code)])
    execute(nb, {"PYVISTA_JUPYTER_BACKEND": "trame"}, timeout=120)
    out = "".join(o.get("text", "") for o in nb.cells[0].outputs if o.output_type == "stream")
    lines = dict(line.split(" ", 1) for line in out.splitlines() if " " in line)
    assert lines.get("band") == "1 0", out  # shown during the drag, gone after
    selected, total, same = lines["selected"].split()
    assert same == "True" and 1 < int(selected) < int(total), out
    assert lines["still"] == "True", out
    assert lines["message"].startswith(f"rectangle: {selected} leaves (replace)"), out
    assert lines["click"] == "True", out
    assert lines["turned"] == "True True", out


def test_the_trame_view_goes_through_jupyters_port_when_it_can(monkeypatch):
    """jupyter-server-proxy importable: the trame view's frame loads from /proxy/PORT/ on the
    Jupyter server; RAMURE_TRAME_PROXY turns it on or off; a choice pyvista was given stays."""
    import importlib.util

    import pyvista as pv

    from ramure.app.jupyter.view import PROXY_SWITCH, trame_proxy

    theme = pv.global_theme.trame
    monkeypatch.setattr(theme, "_server_proxy_enabled", False)
    monkeypatch.setattr(theme, "_server_proxy_prefix", "/proxy/")
    monkeypatch.setattr(theme, "_jupyter_extension_enabled", False)
    monkeypatch.delenv(PROXY_SWITCH, raising=False)
    monkeypatch.delenv("PYVISTA_TRAME_JUPYTER_MODE", raising=False)
    real = importlib.util.find_spec
    installed = {"jupyter_server_proxy": True}

    def find_spec(name, *args):
        if name == "jupyter_server_proxy":
            return real("json") if installed[name] else None
        return real(name, *args)

    monkeypatch.setattr(importlib.util, "find_spec", find_spec)
    assert trame_proxy() == {"server_proxy_enabled": True, "server_proxy_prefix": "/proxy/"}
    installed["jupyter_server_proxy"] = False
    assert trame_proxy()["server_proxy_enabled"] is False  # no proxy to go through
    monkeypatch.setenv(PROXY_SWITCH, "1")
    assert trame_proxy()["server_proxy_enabled"] is True
    installed["jupyter_server_proxy"] = True
    monkeypatch.setenv(PROXY_SWITCH, "off")
    assert trame_proxy()["server_proxy_enabled"] is False
    monkeypatch.delenv(PROXY_SWITCH)
    monkeypatch.setenv("PYVISTA_TRAME_JUPYTER_MODE", "native")  # told to pyvista: kept
    assert trame_proxy()["server_proxy_enabled"] is False
    monkeypatch.setattr(theme, "_server_proxy_enabled", True)  # e.g. on a hub
    monkeypatch.setattr(theme, "_server_proxy_prefix", "/user/ada/proxy/")
    assert trame_proxy() == {"server_proxy_enabled": True, "server_proxy_prefix": "/user/ada/proxy/"}


def test_the_trame_frame_url_in_a_kernel():
    """Only where pyvista's trame backend is installed: in a kernel the view's frame is on
    /proxy/PORT/ (jupyter-server-proxy is installed with Ramure's jupyter extra), and on
    http://localhost:PORT with RAMURE_TRAME_PROXY=0."""
    pytest.importorskip("trame_pyvista")
    pytest.importorskip("jupyter_server_proxy")
    nbformat = pytest.importorskip("nbformat")
    from jupyter_helpers import execute

    code = f"""from ramure.app.jupyter import NotebookExplorer
ex = NotebookExplorer({HONDA!r}, n=3)
print(ex.view.backend, ex.view.trame.widget.src)"""
    for switch, start in (("", "/proxy/"), ("0", "http://localhost:")):
        nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)])
        execute(nb, {"PYVISTA_JUPYTER_BACKEND": "trame", "RAMURE_TRAME_PROXY": switch}, timeout=120)
        out = "".join(o.get("text", "") for o in nb.cells[0].outputs if o.output_type == "stream").split()
        assert out[0] == "server" and out[1].startswith(start) and "/index.html?ui=" in out[1], out


def test_the_picture_view_refuses_the_rectangle_and_says_why():
    ex = NotebookExplorer(HONDA, n=4, view="static")
    assert ex.rectangle.disabled
    ex.set_rectangle_mode(True)
    assert not ex.rectangle.value and "needs the interactive 3D view" in ex.message.text
    assert ex.select_rectangle((0, 0, 400, 400)) is None and ex.selection == []
    assert "needs the interactive 3D view" in ex.message.text
