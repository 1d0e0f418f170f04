"""The notebook's "New study…" under the Variants tab: refused before an exploration, then a servable study."""

from __future__ import annotations

import pytest

from jupyter_helpers import HONDA

pytest.importorskip("metrics")


def test_new_study_button_builds_the_study_and_shows_the_serve_command(tmp_path):
    from ramure.app.jupyter import NotebookExplorer
    from ramure.studies.serve import check_servable
    from ramure.studies.storage import Study

    ex = NotebookExplorer(HONDA, n=3, view="static", size=(120, 120), cache=False)
    panel = ex.study_maker
    titles = [ex.tabs.get_title(i) for i in range(len(ex.tabs.children))]
    assert panel.widget in ex.tabs.children[titles.index("Variants")].children
    panel.folder.value = str(tmp_path / "s")
    panel.create_button.click()  # nothing explored yet: refused on the panel, nothing written
    assert "explore the variants first" in panel.message.text and not (tmp_path / "s").exists()
    ex.variants.thumb_size = 40
    ex.explore_variants(n=3, n_jobs=1)
    panel.title.value = "Notebook pilot"
    panel.minutes.value = 20
    panel.create_button.click()
    db = tmp_path / "s" / "study.db"
    assert panel.made is not None and panel.made.db == db, panel.message.text
    assert f"ramure study serve {db}" in panel.command.value
    with Study.open(db, readonly=True) as study:
        assert study.name == "Notebook pilot" and study.budget_seconds == 20 * 60
        assert [p.variant for p in study.picks("honda_sympodial")] == ex.variants.exploration.picks.variant.tolist()
        check_servable(study)
    # again into the same folder: refused, shown, the study kept
    before = db.read_bytes()
    assert ex.new_study(tmp_path / "s") is None
    assert "already holds a study" in panel.message.text and db.read_bytes() == before
    panel.add_to.value = True  # one more part: refused under the same name, added under another
    panel.create_button.click()
    assert "already holds a stimulus set named 'honda_sympodial'" in panel.message.text
    ex.variants.exploration.name = "second"
    assert ex.new_study(tmp_path / "s", add=True) is not None and panel.message.text.startswith("added to the study")
    with Study.open(db, readonly=True) as study:
        assert study.grammars == ["honda_sympodial", "second"] and study.name == "Notebook pilot"
