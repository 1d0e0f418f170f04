"""Issue 35 in the notebook: the collision matrix as a heat map, typed words with suggestions,
and a study's words as qualifiers."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest

from ramure.app.jupyter import NotebookExplorer
from jupyter_helpers import HONDA


@pytest.fixture(scope="module")
def explored():
    ex = NotebookExplorer(HONDA, n=4, view="static", size=(160, 160), cache=False)
    exp = ex.variants.explore(n=4, n_jobs=1, thumbnails=False)
    return ex, exp


@pytest.fixture
def ex(explored):
    source, exp = explored
    fresh = NotebookExplorer(HONDA, n=4, view="static", size=(160, 160), cache=False)
    fresh.variants.exploration = exp
    fresh.variants.refresh()
    fresh.refresh()
    return fresh


def click_apply(ex, monkeypatch):
    """Click Apply in the qualifier row; returns what the qualifier did (None when refused)."""
    seen = []
    real = ex.variants.apply_qualifier
    monkeypatch.setattr(ex.variants, "apply_qualifier", lambda name: seen.append(real(name)) or seen[-1])
    ex.edits.apply_qualifier.click()
    monkeypatch.setattr(ex.variants, "apply_qualifier", real)
    return seen[-1] if seen else None


def _labels(ax):
    return [t.get_text() for t in ax.get_yticklabels()]


def test_the_collision_matrix_is_a_heat_map_of_the_api_matrix(explored, tmp_path):
    from PIL import Image

    from ramure.metrics.qualifiers import vocabulary_regions

    ex, exp = explored
    panel = ex.variants
    api = vocabulary_regions(exp.sweep, exp.points)  # what `ramure qualify --matrix` prints
    ax = panel.matrix_figure.axes[0]
    drawn = np.asarray(ax.images[0].get_array().filled(np.nan), float)
    off = ~np.eye(len(api.names_), dtype=bool)
    assert _labels(ax) == api.names_ and drawn.shape == api.collision_matrix_.shape
    assert np.allclose(drawn[off], api.collision_matrix_[off]) and np.isnan(np.diag(drawn)).all()
    texts = [t.get_text() for t in ax.texts]  # each cell carries its value
    assert texts.count(f"{api.collision_matrix_[0, 1]:.0f}") >= 1 and len(texts) == off.sum()
    assert f"mean {api.mean_collision():.1f} %" in panel.matrix_note.value
    png = panel.matrix.value
    (tmp_path / "matrix.png").write_bytes(png)
    image = np.asarray(Image.open(io.BytesIO(png)).convert("L"), float)
    assert image.shape[0] > 300 and image.std() > 20  # a drawn heat map, not a blank picture
    assert panel.matrix in panel.pca_widget.children  # in the PCA & qualifiers tab
    panel.matrix_french.value = True  # the checkbox redraws it with the French names
    french = _labels(panel.matrix_figure.axes[0])
    assert "petit" in french and "haut" in french and "small" not in french
    assert panel.matrix.value != png
    panel.matrix_french.value = False
    figure = panel.matrix_figure
    panel.refresh()  # nothing changed: not drawn again (a second of matplotlib text)
    assert panel.matrix_figure is figure


def test_the_matrix_shows_a_studys_regions_when_loaded(ex, tmp_path):
    from ramure.metrics.store import QualifierStore

    exp = ex.variants.exploration
    with QualifierStore(tmp_path / "q.sqlite") as store:
        for word, pick in (("petit", 0), ("dense", 26)):
            near = np.argsort(np.linalg.norm(exp.points - exp.picks.points[pick], axis=1))[:6]
            store.add(exp.name, word, near, exp.points[near], [exp.sweep.combination(int(i)) for i in near], source="study:t")
    regions = ex.load_qualifiers(tmp_path / "q.sqlite")
    ax = ex.variants.matrix_figure.axes[0]
    assert [t.get_text() for t in ax.get_yticklabels()] == ["dense", "small"] == regions.names_
    drawn = np.asarray(ax.images[0].get_array().filled(np.nan), float)
    assert drawn[0, 1] == pytest.approx(regions.collision_matrix_[0, 1])
    assert "the study's regions" in ex.variants.matrix_note.value


def test_the_matrix_waits_for_an_exploration():
    fresh = NotebookExplorer(HONDA, n=3, view="static", size=(120, 120), cache=False)
    assert fresh.variants.matrix.value == b"" and fresh.variants.matrix_figure is None
    assert "explore the variants first" in fresh.variants.matrix_note.value


def test_typed_words_reach_the_model(ex, monkeypatch):
    box = ex.edits.qualifier
    assert {"taller", "denser", "plus haut", "touffu", "étroit"} <= set(box.options)
    box.value = "Plus Haut"  # French comparative, any case
    result = click_apply(ex, monkeypatch)
    assert result.qualifier == "tall" and ex.error is None
    if result.improved:
        assert result.after_shape.height > result.before_shape.height


def test_a_refused_word_names_close_words_before_any_exploration():
    fresh = NotebookExplorer(HONDA, n=3, view="static", size=(120, 120), cache=False)
    fresh.edits.qualifier.value = "taler"
    fresh.edits.apply_qualifier.click()
    assert "unknown qualifier 'taler'" in fresh.error and "did you mean taller" in fresh.error
    assert fresh.variants.exploration is None  # refused before the (slow) exploration
    fresh.edits.qualifier.value = "  "
    fresh.edits.apply_qualifier.click()
    assert "type or choose a qualifier" in fresh.message.text


def test_a_study_word_is_suggested_and_applied_with_its_direction(ex, tmp_path, monkeypatch):
    path = tmp_path / "words.json"
    doc = {"format": "ramure-words", "words": {"long-trunk": {"direction": {"height": 1.0, "crown_width": -0.3}}}}
    path.write_text(json.dumps(doc))
    ex.variants.words_path.value = str(path)  # the PCA & qualifiers tab's field and button
    ex.variants.load_words_button.click()
    assert ex.variants.words == {"long-trunk": {"height": 1.0, "crown_width": -0.3}}
    assert "long trunk" in ex.edits.qualifier.options and "1 study words" in ex.message.text
    ex.edits.qualifier.value = "Long trunk"
    result = click_apply(ex, monkeypatch)
    assert ex.error is None and result.qualifier == "long-trunk" and result.source == "transfer"
    assert ex.message.text.startswith("'long-trunk'")  # what it did, or why it did nothing
    assert "long-trunk" in result.moves  # scored along its own direction, like any qualifier
    assert result.moves["long-trunk"] > 0 if result.improved else result.reason
    ex.edits.qualifier.value = "long trunc"
    ex.edits.apply_qualifier.click()
    assert "did you mean long trunk" in ex.error
    (tmp_path / "bad.json").write_text("[1]")
    assert ex.load_words(tmp_path / "bad.json") is None and "not a Ramure vocabulary file" in ex.error
    assert ex.variants.words  # the words loaded before stay


def test_a_study_word_that_moved_nothing_says_why():
    from types import SimpleNamespace as NS

    from ramure.app.jupyter.variants import qualifier_summary

    result = NS(qualifier="long-trunk", improved=False, tried=0, params={}, regen=None, reason="every variant moves X more")
    assert qualifier_summary(result) == (
        "'long-trunk' did not move the selection its way after 0 tries; the plant is as it was: every variant moves X more"
    )
    result.regen, result.improved, result.params = object(), True, {"rule": 2}
    assert qualifier_summary(result) == "'long-trunk': applied {'rule': 2}"
