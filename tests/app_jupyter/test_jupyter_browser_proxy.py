"""The trame view through Jupyter's own port, and its rubber band, in headless Chromium.

JupyterLab runs with jupyter-server-proxy (installed with Ramure's jupyter extra); a notebook
makes an explorer.  The 3D view's frame must load from ``/proxy/PORT/`` on the Jupyter server
and every request and websocket the page opens must go to Jupyter's port: what a JupyterHub or
an SSH tunnel forwarding that port only lets through.  Then the ▭ rectangle button and a drag
in the view select the branches inside the band, the camera staying still.

Screenshots go to tests/artifacts/browser/.  Select it alone with ``pytest -m browser``.
"""

from __future__ import annotations

import pytest

from jupyter_helpers import HONDA

pytest.importorskip("jupyterlab")
pytest.importorskip("trame_pyvista")
pytest.importorskip("jupyter_server_proxy")
sync_api = pytest.importorskip("playwright.sync_api")
nbformat = pytest.importorskip("nbformat")

from browser_helpers import Lab, chromium_available, launch_chromium, picture_stats  # noqa: E402
from test_jupyter_browser import ALL_RAN, KERNEL_IDLE, _poll, _run_code, _save, _view_png  # noqa: E402

pytestmark = [pytest.mark.browser, pytest.mark.timeout(300)]


def _reddish(png) -> int:
    """Pixels clearly red (the band's thin line comes back smoothed: a loose test)."""
    import io

    import numpy as np
    from matplotlib.image import imread

    rgb = imread(io.BytesIO(png), format="png")[..., :3]
    return int(np.sum((rgb[..., 0] > 0.5) & (rgb[..., 0] - rgb[..., 1:].max(axis=2) > 0.3)))


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    if not chromium_available():
        pytest.skip("Debian's chromium is not installed (make test's system step installs it)")
    root = tmp_path_factory.mktemp("proxylab")
    code = f"from ramure.app.jupyter import NotebookExplorer\nex = NotebookExplorer({HONDA!r}, n=6, cache=False)\nex"
    kernel = {"kernelspec": {"name": "python3", "display_name": "Python 3", "language": "python"}}  # no kernel dialog
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)], metadata=kernel)
    nbformat.write(nb, root / "proxy.ipynb")
    server = Lab(root, env={"RAMURE_CACHE": str(root / "cache")})
    server.settings("@jupyterlab/notebook-extension:tracker", {"windowingMode": "none"})
    server.settings("@jupyterlab/apputils-extension:notification", {"fetchNews": "false"})
    server.start()
    yield server
    server.stop()


def test_the_view_through_the_proxy_and_its_rubber_band(lab):
    with sync_api.sync_playwright() as playwright:
        browser = launch_chromium(playwright)
        try:
            page = browser.new_page(viewport={"width": 1500, "height": 1100})
            elsewhere = []  # requests and websockets to any other port than Jupyter's
            jupyter = f"127.0.0.1:{lab.port}"

            def check(url):
                if url.startswith(("http", "ws")) and url.split("/")[2] != jupyter:
                    elsewhere.append(url)

            page.on("request", lambda request: check(request.url))
            page.on("websocket", lambda socket: check(socket.url))
            page.goto(lab.url("lab/tree/proxy.ipynb"))
            page.wait_for_function(KERNEL_IDLE, timeout=90_000)
            page.evaluate("window.jupyterapp.commands.execute('notebook:run-all-cells')")
            page.wait_for_function(ALL_RAN, timeout=180_000)
            cell = page.locator(".jp-CodeCell").first
            view = cell.locator("iframe").first
            view.wait_for(timeout=30_000)
            src = view.get_attribute("src")
            assert src.startswith("/proxy/") and "/index.html?ui=" in src, src
            first = _view_png(view, settle=2.0)
            stats = picture_stats(first)
            assert stats["drawn"] > 0.01 and stats["colours"] > 20, stats  # drawn through the proxy
            status, out = _run_code(page, "print(ex.view.backend, ex.view.trame.plotter.camera_position)")
            assert status == "ok" and out.startswith("server"), out
            camera = out.split(" ", 1)[1].strip()

            # ▭ rectangle, then a drag over the upper right of the view
            cell.get_by_role("button", name="▭ rectangle").click()
            _poll(page, "print(ex.view.trame.rectangle.enabled)", lambda out: out.strip() == "True")
            box = view.bounding_box()
            (x0, y0), (x1, y1) = (0.45, 0.25), (0.95, 0.7)
            page.mouse.move(box["x"] + x0 * box["width"], box["y"] + y0 * box["height"])
            page.mouse.down()
            for step in range(1, 11):
                t = step / 10
                page.mouse.move(box["x"] + (x0 + t * (x1 - x0)) * box["width"], box["y"] + (y0 + t * (y1 - y0)) * box["height"])
            banded = _view_png(view, first, timeout=5.0, settle=0.6)  # the band drawn
            page.mouse.up()
            _save("proxy_band.png", banded)
            assert _reddish(first) == 0 and _reddish(banded) > 400, (_reddish(first), _reddish(banded))  # the band showed
            out = _poll(
                page,
                "print(len(ex.selection), '|', ex.view.trame.last_rectangle, '|', ex.view.trame.plotter.window_size, '|', "
                "len(set(ex.skeleton.leaf_id.tolist())), '|', ex.message.text)",
                lambda out: not out.startswith("0 |"),
            )
            count, rect, size, leaves, message = (part.strip() for part in out.split("|", 4))
            assert 1 < int(count) < int(leaves), out
            assert message.startswith(f"rectangle: {count} leaves (replace)"), out
            # the band the kernel measured is the one dragged (VTK counts y from the bottom)
            w, h = (int(v) for v in size.strip("()[]").split(","))
            got = [int(v) for v in rect.strip("()").split(",")]
            want = [x0 * w, (1 - y0) * h, x1 * w, (1 - y1) * h]
            assert all(abs(g - e) <= 0.02 * max(w, h) for g, e in zip(got, want)), (got, want)
            status, out = _run_code(
                page,
                "print(ex.selection == ex.model.leaves_in_view(*ex.view.trame.camera(), ex.view.trame.last_rectangle), "
                "ex.view.trame.plotter.camera_position)",
            )
            same, still = out.split(" ", 1)
            assert same == "True" and still.strip() == camera, out
            selected = _view_png(view, first)
            _save("proxy_view.png", first)
            _save("proxy_rectangle.png", selected)
            assert picture_stats(selected)["drawn"] > 0.01
            assert elsewhere == [], elsewhere[:5]  # Jupyter's port only
        finally:
            browser.close()
