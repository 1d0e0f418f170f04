"""The two example notebooks run headless (nbclient) without error and produce their outputs."""

from __future__ import annotations

import base64
import re

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

from jupyter_helpers import ROOT, execute  # noqa: E402


def run_notebook(name, tmp_path):
    nb = nbformat.read(ROOT / "examples" / name, as_version=4)
    return execute(nb, {"PYVISTA_JUPYTER_BACKEND": "static", "RAMURE_CACHE": str(tmp_path / "cache")})


def outputs(nb):
    return [o for cell in nb.cells if cell.cell_type == "code" for o in cell.outputs]


def text_of(nb):
    return "".join(o.get("text", "") for o in outputs(nb) if o.output_type == "stream")


@pytest.mark.slow
def test_explore_notebook_runs(tmp_path):
    nb = run_notebook("explore.ipynb", tmp_path)
    assert not [o for o in outputs(nb) if o.output_type == "error"]
    widget, fallback = (o["data"] for o in nb.cells[1].outputs)
    # the explorer shows as a widget, then its picture in an output of its own: what a notebook
    # reopened without a kernel shows (the widget output then has no model)
    assert "application/vnd.jupyter.widget-view+json" in widget and "image/png" not in widget
    assert base64.b64decode(fallback["image/png"])[:4] == b"\x89PNG"
    assert "ramure-fallback" in fallback["text/html"] and "Ramure explorer — honda_sympodial" in fallback["text/html"]
    text = text_of(nb)
    assert "Traceback" not in text and "Downloaded WASM" not in text
    assert "undo restores the plant: True" in text
    assert "changed: True | last edit: regrow {'a2': 30.0}" in text
    assert "replays to the same plant: True" in text
    assert re.search(r"thicker: mean radius [\d.]+ → [\d.]+", text) and "one more edit: True" in text
    assert "regrew 1 fruit as pear (seed" in text or "not available in this version" in text
    assert re.search(r"the pear: \d+ volume cells in [3-9] tissues", text) or "not available in this version" in text
    pngs = [o for o in outputs(nb) if "image/png" in o.get("data", {})]
    assert len(pngs) >= 4  # explorer, selection, regrown plant, pick
    pictures = [
        o["data"]["text/html"]
        for o in outputs(nb)
        if "text/html" in o.get("data", {})
        and "data:image/png" in o["data"]["text/html"]
        and "Ramure explorer" not in o["data"]["text/html"]
        and "title='PCA'" not in o["data"]["text/html"]
    ]
    assert pictures and pictures[0].count("<img") == 27  # the gallery
    assert "the plant after &#x27;thick&#x27;" in pictures[1] and pictures[1].count("<img") == 2  # with the PCA view
    if "not available in this version" not in text:
        assert "after Regrow fruit: a pear" in pictures[2] and pictures[2].count("<img") == 3
        assert "the pear cut across its axis" in pictures[3] and pictures[3].count("<img") == 2


@pytest.mark.slow
def test_study_notebook_runs(tmp_path):
    nb = run_notebook("study.ipynb", tmp_path)
    assert not [o for o in outputs(nb) if o.output_type == "error"]
    text = text_of(nb)
    assert "27 thumbnails" in text
    assert "finished: True" in text
    assert "12 simulated participants; 13 finished tests" in text
    report = [
        o["data"]["text/html"]
        for o in outputs(nb)
        if "text/html" in o.get("data", {}) and "ramure-report" in o["data"]["text/html"]
    ]
    assert report, "the analysis cell renders the report inline"
    assert "13 participants" in report[0] and "data:image/png;base64" in report[0]
