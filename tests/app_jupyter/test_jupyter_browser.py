"""examples/explore.ipynb in JupyterLab inside headless Chromium, as a user runs it.

JupyterLab is started on 127.0.0.1 with its default settings (comms over subshells on, so
widget callbacks arrive on kernel threads), Debian's chromium is driven by Playwright's Python
package over the DevTools protocol (no browser download).  The test runs every cell, checks the
explorer rendered, clicks a variant thumbnail, changes the view three times (the 3D view is not
blank), clicks a branch (one leaf selected), drags from a branch (the view turns, the selection
stays), checks the kernel is alive, then saves and reloads the page: the explorer's output shows
its picture, not "Error displaying widget: model not found".

Screenshots go to tests/artifacts/browser/.  Select it alone with ``pytest -m browser``.
"""

from __future__ import annotations

import shutil
import time

import pytest

from jupyter_helpers import ROOT
from ramure.app.jupyter.view import TOOLBAR_BAND

pytest.importorskip("jupyterlab")
pytest.importorskip("trame_pyvista")
sync_api = pytest.importorskip("playwright.sync_api")

from browser_helpers import Lab, chromium_available, launch_chromium, picture_stats  # noqa: E402

pytestmark = [pytest.mark.browser, pytest.mark.timeout(420)]

ARTIFACTS = ROOT / "tests" / "artifacts" / "browser"
#: Images shown in the explorer's cell that failed to load: the browser's broken-image icon.
BROKEN_IMAGES = """() => Array.from(document.querySelectorAll('.jp-CodeCell')[0].querySelectorAll('img'))
  .filter(i => i.offsetParent && i.complete && i.naturalWidth === 0).map(i => i.outerHTML.slice(0, 80))"""
KERNEL_IDLE = """() => { const w = window.jupyterapp && window.jupyterapp.shell.currentWidget;
  const k = w && w.sessionContext && w.sessionContext.session && w.sessionContext.session.kernel;
  return !!k && k.status === 'idle'; }"""
ALL_RAN = """() => { const w = window.jupyterapp.shell.currentWidget;
  if (w.sessionContext.session.kernel.status !== 'idle') return false;
  const cells = w.content.widgets.filter(c => c.model.type === 'code');
  const failed = cells.some(c => Array.from({length: c.model.outputs.length}, (_, i) => c.model.outputs.get(i))
                                      .some(o => o.type === 'error'));
  return failed || cells.every(c => c.model.executionCount !== null); }"""


def _run_code(page, code):
    """Run ``code`` in the notebook's kernel; returns (status, text printed)."""
    return page.evaluate(
        """async (code) => {
      const kernel = window.jupyterapp.shell.currentWidget.sessionContext.session.kernel;
      let text = '';
      const future = kernel.requestExecute({code, store_history: false});
      future.onIOPub = (msg) => { if (msg.header.msg_type === 'stream') text += msg.content.text; };
      const reply = await future.done;
      return [reply.content.status, text]; }""",
        code,
    )


def _poll(page, code, done, timeout=20.0):
    """Run ``code`` until ``done(printed)`` or the timeout; returns the last text printed."""
    deadline = time.monotonic() + timeout
    while True:
        status, out = _run_code(page, code)
        if (status == "ok" and done(out)) or time.monotonic() > deadline:
            return out
        time.sleep(0.5)


def _view_png(view, previous=None, timeout=15.0, settle=1.2):
    """A screenshot of the 3D view once it differs from ``previous`` (a redraw) and then stays the
    same for ``settle`` seconds (a redraw can arrive in several frames)."""
    deadline = time.monotonic() + timeout
    png = view.screenshot()
    while previous is not None and png == previous and time.monotonic() < deadline:
        time.sleep(0.3)
        png = view.screenshot()
    stable = time.monotonic()
    while time.monotonic() - stable < settle and time.monotonic() < deadline:
        time.sleep(0.3)
        again = view.screenshot()
        if again != png:
            png, stable = again, time.monotonic()
    return png


def _plant_top(png):
    """How far down the view the plant starts (a fraction of its height): the first row with a
    bark, leaf or fruit pixel (brown, green, orange or red; pyvista's menu is grey and blue)."""
    import io

    import numpy as np
    from matplotlib.image import imread

    rgb = imread(io.BytesIO(png), format="png")[..., :3]
    plant = np.max(rgb[..., :2], axis=2) - rgb[..., 2] > 0.12
    rows = np.flatnonzero(plant.any(axis=1))
    return rows.min() / len(rgb) if len(rows) else 1.0


def _save(name, png):
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    (ARTIFACTS / name).write_bytes(png)


def _dark_pixel(png):
    """(x, y) of a bark-coloured pixel near the middle of the drawn plant, or None."""
    import io

    import numpy as np
    from matplotlib.image import imread

    rgb = imread(io.BytesIO(png), format="png")[..., :3]
    rgb[:80] = 1.0  # pyvista's menu bar (grey icons) shows over the top of the view on hover
    dark = np.argwhere((rgb.max(axis=2) < 0.5) & (rgb[..., 0] - rgb[..., 2] > 0.06))  # bark brown
    if not len(dark):
        return None
    centre = dark.mean(axis=0)
    y, x = dark[np.argmin(np.linalg.norm(dark - centre, axis=1))]
    return int(x), int(y)


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    if not chromium_available():
        pytest.skip("Debian's chromium is not installed (make test's system step installs it)")
    root = tmp_path_factory.mktemp("lab")
    shutil.copy(ROOT / "examples" / "explore.ipynb", root / "explore.ipynb")  # the repository copy stays clean
    server = Lab(root, env={"RAMURE_CACHE": str(root / "cache")})
    server.settings("@jupyterlab/notebook-extension:tracker", {"windowingMode": "none"})  # every cell in the DOM
    server.settings("@jupyterlab/apputils-extension:notification", {"fetchNews": "false"})
    server.start()
    yield server
    server.stop()


def test_explore_notebook_in_chromium(lab):
    with sync_api.sync_playwright() as playwright:
        browser = launch_chromium(playwright)
        try:
            page = browser.new_page(viewport={"width": 1500, "height": 1100})
            page.goto(lab.url("lab/tree/explore.ipynb"))
            page.wait_for_function(KERNEL_IDLE, timeout=90_000)
            page.evaluate("window.jupyterapp.commands.execute('notebook:run-all-cells')")
            page.wait_for_function(ALL_RAN, timeout=240_000)
            notebook = page.locator(".jp-Notebook")
            errors = page.locator(".jp-OutputArea-output[data-mime-type='application/vnd.jupyter.stderr']")
            tracebacks = [t for t in errors.all_text_contents() if "Error" in t]
            assert not tracebacks, tracebacks[0][-2000:]  # a cell failed: run-all stopped there
            text = notebook.text_content()
            assert "Loading widget" not in text and "Error displaying widget" not in text
            assert "Traceback" not in text and "Downloaded WASM" not in text
            cell = page.locator(".jp-CodeCell").first
            explorer = cell.locator(".widget-vbox").first
            explorer.scroll_into_view_if_needed()
            assert "Ramure explorer" in explorer.text_content()
            truncated = page.evaluate("""() => Array.from(document.querySelectorAll('.jp-CodeCell')[0]
                .querySelectorAll('button')).filter(b => b.offsetParent && b.scrollWidth > b.clientWidth + 1)
                .map(b => b.textContent)""")
            assert not truncated, f"truncated button labels: {truncated}"
            _save("explorer.png", cell.screenshot())

            # before their first action the picture tabs show no broken-image icon; the
            # Architecture tab's buttons are disabled for Honda's grammar (no #amap)
            for name in ("Wood", "Details", "Defects"):
                cell.get_by_role("tab", name=name).click()
                assert page.evaluate(BROKEN_IMAGES) == [], name
            cell.get_by_role("tab", name="Architecture").click()
            sync_api.expect(cell.get_by_text("names no architecture", exact=False).first).to_be_visible()
            for name in ("Open ▸", "◂ Up", "Top", "Select"):
                sync_api.expect(cell.get_by_role("button", name=name, exact=True)).to_be_disabled()

            view = cell.locator("iframe").first
            view.wait_for(timeout=30_000)
            first = _view_png(view)
            # a variant thumbnail: the Variants tab, then pick #5
            cell.get_by_role("tab", name="Variants").click()
            pick = cell.get_by_role("button", name="#5", exact=True)
            pick.click()
            message = cell.locator("pre").first
            sync_api.expect(message).to_contain_text("applied pick #5", timeout=30_000)
            after_pick = _view_png(view, first)
            _save("after_pick.png", after_pick)

            # three view presets: each one drawn, not blank, different from the last
            camera = cell.locator("select").filter(has=page.locator("option", has_text="front")).first
            shots = [after_pick]
            for side in ("front", "top", "side"):
                camera.select_option(label=side)
                png = _view_png(view, shots[-1])
                stats = picture_stats(png)
                _save(f"view_{side}.png", png)
                assert stats["drawn"] > 0.01 and stats["colours"] > 20, (side, stats)
                assert stats["background"][0] > 200, (side, stats)  # white, not a black (dead) view
                shots.append(png)
            assert len({bytes(s) for s in shots}) == 4
            # nothing under pyvista's menu: the menu card hides what is under it, so a plant cut
            # off by it starts right at the card's lower edge (56 px down); one framed below the
            # band starts some 24 px lower than the band (the 10 % margin of fit_view)
            for side, png in zip(("front", "top", "side"), shots[1:]):
                assert _plant_top(png) >= (TOOLBAR_BAND + 12) / (480 + TOOLBAR_BAND), (side, _plant_top(png))

            # a click on a branch selects its leaf; a drag from a branch turns the view
            spot = _dark_pixel(shots[-1])
            assert spot is not None
            view.click(position={"x": spot[0], "y": spot[1]})
            out = _poll(page, "print(len(ex.selection), '|', ex.message.text)", lambda out: out.startswith("1 |"))
            assert out.startswith("1 |"), (spot, out)
            sync_api.expect(cell.get_by_text("1 selected", exact=False).first).to_be_visible(timeout=10_000)
            clicked = _view_png(view, shots[-1])
            box = view.bounding_box()
            page.mouse.move(box["x"] + spot[0], box["y"] + spot[1])
            page.mouse.down()
            for step in range(1, 9):
                page.mouse.move(box["x"] + spot[0] + 12 * step, box["y"] + spot[1] + 3 * step)
            page.mouse.up()
            turned = _view_png(view, clicked)
            _save("after_drag.png", turned)
            assert turned != clicked and picture_stats(turned)["drawn"] > 0.01
            status, out = _run_code(page, "print(len(ex.selection), ex.view.backend)")
            assert status == "ok" and out.split() == ["1", "server"], out

            problems = [w for w in ("Traceback", "Encountered issue", "Error") if w in notebook.text_content()]
            assert not problems, problems  # nothing printed by the clicks, drags and redraws

            # the kernel is alive and still answers
            assert [k["execution_state"] for k in lab.kernels()] == ["idle"]

            # saved, the kernel shut down, reopened: the explorer's output shows its picture
            page.evaluate("window.jupyterapp.commands.execute('docmanager:save')")
            page.wait_for_function("() => !window.jupyterapp.shell.currentWidget.context.model.dirty", timeout=20_000)
            page.close()
            lab.shutdown_kernels()
            page = browser.new_page(viewport={"width": 1500, "height": 1100})
            page.goto(lab.url("lab/tree/explore.ipynb"))
            page.wait_for_function(KERNEL_IDLE, timeout=90_000)  # a new kernel: no widget models
            cell = page.locator(".jp-CodeCell").first
            fallback = cell.locator(".ramure-fallback img").first
            sync_api.expect(fallback).to_be_visible(timeout=30_000)
            widget_output = cell.locator(".jp-OutputArea-output", has_text="model not found").first
            widget_output.wait_for(state="attached", timeout=60_000)  # the widget output has no model
            sync_api.expect(widget_output).to_be_hidden()  # ... and its error line is not shown
            sync_api.expect(fallback).to_be_visible()
            _save("reopened.png", cell.screenshot())
        finally:
            browser.close()
