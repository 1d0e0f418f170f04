"""Study mode widgets (one participant's test, stored through the SQLite layer) and the inline report."""

from __future__ import annotations

import pytest

from ramure.app.jupyter import StudyPanel, report_html
from ramure.studies import Study, StudyInputError, lattice_picks, load_study_data, simulate_study
from ramure.studies.picks import Pick


@pytest.fixture
def study(tmp_path):
    s = Study.create(tmp_path / "study.db", grammars={"honda": lattice_picks(seed=3)}, name="jupyter")
    yield s
    s.close()


@pytest.fixture
def panel(study):
    return StudyPanel(study, study.add_participant(consent=True), "honda", thumb_size=40)


def test_cards_follow_the_participants_order(panel):
    order = panel.session.order()
    assert list(panel.group_of) == order and sorted(order) == list(range(1, 28))
    labels = [card.children[1].children[0].value for card in panel.grid.children]
    assert labels == [panel.session.labels()[i] for i in order]  # the participant's codes, never pick ids
    assert "in progress" not in panel.header.value and "min left" in panel.header.value


def test_a_whole_test_through_the_widgets(panel, study):
    for image, dropdown in panel.group_of.items():  # each change is stored at once
        dropdown.value = 1 if image <= 9 else (2 if image <= 26 else 3)
    groups = panel.session.groups()
    assert [(g.label, len(g.images)) for g in groups] == [(1, 9), (2, 17), (3, 1)]
    assert len(panel.questions.children) == 3
    form = panel.forms[1]
    form.representative.value = 4
    form.usefulness.value = "good"
    form.difference.value = "fair"
    form.quality.value = "excellent"
    form.qualifiers.value = "petit, dense"
    panel.forms[2].representative.value = 20
    for label in (2, 3):
        f = panel.forms[label]
        f.usefulness.value, f.difference.value = "fair", "poor"
        f.qualifiers.value = "grand"
    panel.forms[2].quality.value = "good"
    assert panel.forms[3].representative.layout.display == "none"  # single image: no representative
    panel.finish_button.click()
    assert panel.session.finished and "thank you" in panel.message.text
    assert all(d.disabled for d in panel.group_of.values()) and panel.finish_button.disabled
    stored = panel.session.groups()[0]
    assert (stored.representative, stored.usefulness, stored.difference, stored.representative_quality, stored.qualifiers) == (
        4,
        3,
        2,
        4,
        ["petit", "dense"],
    )
    data = load_study_data(study)
    assert data.n_tests == 1


def test_finish_lists_what_is_missing(panel):
    panel.assign([range(1, 28)])
    panel.finish()
    assert not panel.session.finished and panel.message.kind == "error"
    assert "group 1: choose a representative" in panel.message.text
    assert "group 1: rate its usefulness" in panel.todo.value


def test_refused_answer_is_shown_and_undone_on_screen(panel):
    panel.assign({i: 1 for i in range(1, 28)})
    panel.forms[1].quality.value = "good"  # rating the representative before choosing it
    assert panel.message.kind == "error" and "choose its representative" in panel.message.text
    assert panel.forms[1].quality.value is None and panel.session.groups()[0].representative_quality is None


def test_group_numbers_stay_as_given_and_are_stored_in_order(panel, study):
    panel.group_of[14].value = 2  # one image at a time, starting with group 2
    panel.group_of[3].value = 1
    panel.group_of[5].value = 2
    assert panel.group_of[14].value == 2  # not renumbered under the participant's hands
    assert [g.images for g in panel.session.groups()] == [[3], [5, 14]]
    assert [f.number for f in panel.forms.values()] == [1, 2]
    panel.assign({i: (2 if i % 2 else 5) for i in range(1, 28)})
    assert [len(g.images) for g in panel.session.groups()] == [14, 13]
    panel.answer(5, usefulness="good")
    assert panel.session.groups()[1].usefulness == 3 and "Group 5" in panel.forms[5].widget.children[0].value
    resumed = StudyPanel(study, panel.session.participant, "honda")
    assert resumed.group_of[1].value == 1 and resumed.group_of[2].value == 2


def test_answer_and_qualifier_sync(panel):
    panel.assign([range(1, 14), range(14, 28)])
    panel.answer(1, representative=5, usefulness="excellent", qualifiers=["petit", "épars"])
    panel.answer(1, qualifiers="épars")
    g = panel.session.groups()[0]
    assert g.representative == 5 and g.usefulness == 4 and g.qualifiers == ["épars"]
    panel.answer(7, usefulness="good")
    assert "group 7 does not exist" in panel.message.text


def test_thumbnails_from_pick_images(tmp_path):
    from ramure.app.jupyter.view import mesh_png
    from ramure.app.model import Explorer

    png = mesh_png(Explorer("n: 1\nw: F").mesh, size=(32, 32))
    (tmp_path / "img.png").write_bytes(png)
    picks = [Pick(p.id, p.variant, p.pca, p.params, str(tmp_path / "img.png") if p.id == 2 else None) for p in lattice_picks()]
    with Study.create(tmp_path / "s.db", grammars={"g": picks}) as study:
        panel = StudyPanel(study, study.add_participant(consent=True), "g", thumb_size=32)
        card = panel.grid.children[panel.session.order().index(2)]
        assert card.children[0].value == png
        other = panel.grid.children[panel.session.order().index(1)]
        assert "no picture" in other.children[0].value and "#1" not in other.children[0].value  # a placeholder, no pick id
        panel.assign({2: 4})
        page = panel.screen_html()  # the fallback output: what a notebook reopened without a kernel shows
        label = panel.session.labels()
        assert page.count("data:image/png") == 1 and f"{label[2]} · group 4" in page and f"{label[1]} · unsorted" in page


def test_no_consent_is_refused(study):
    code = study.add_participant(consent=False)
    with pytest.raises(StudyInputError, match="consent"):
        StudyPanel(study, code, "honda")


def test_report_inline_is_self_contained(tmp_path):
    data = simulate_study(participants=4, grammars=2, seed=2)
    html = report_html(data, out_dir=tmp_path / "r")
    assert (tmp_path / "r" / "index.html").is_file()
    assert html.startswith("<div class='ramure-report'>") and "4 participants, 8 finished tests" in html
    figures = len(list((tmp_path / "r").glob("*.png")))
    assert figures >= 4 and html.count("data:image/png;base64,") == figures and "src='cooccurrence.png'" not in html
    assert "<body" not in html and ".ramure-report table{" in html and "}body{" not in html
    # the table links download the files themselves (a relative link 404s in JupyterLab)
    import base64
    import re

    links = dict((name, data) for data, name in re.findall(r"href='data:[^;]+;base64,([^']+)' download='([^']+)'", html))
    assert "summary.json" in links and "anova.csv" in links
    assert base64.b64decode(links["anova.csv"]) == (tmp_path / "r" / "anova.csv").read_bytes()
    assert not re.search(r"href='(?!data:|#)", html)


def answer_both(panel):
    """Two groups (images 1-9 and 10-18) answered through their widgets."""
    panel.assign([range(1, 10), range(10, 19)])
    panel.answer(1, representative=5, usefulness="good", difference="fair", quality="excellent", qualifiers="petit")
    panel.answer(2, representative=14, usefulness="poor", difference="good", quality="fair", qualifiers="grand, dense")


def on_screen(form):
    return (form.representative.value, form.usefulness.value, form.difference.value, form.quality.value, form.qualifiers.value)


def test_moving_a_picture_between_answered_groups_keeps_both(panel, study):
    answer_both(panel)
    panel.group_of[3].value = 2  # the participant moves picture 3 from group 1 to group 2
    assert panel.message.kind != "error"
    assert on_screen(panel.forms[1]) == (5, "good", "fair", "excellent", "petit")
    assert on_screen(panel.forms[2]) == (14, "poor", "good", "fair", "grand, dense")
    panel.group_of[14].value = 1  # group 2's representative moves: only it (and its rating) is cleared
    assert on_screen(panel.forms[1]) == (5, "good", "fair", "excellent", "petit")
    assert on_screen(panel.forms[2]) == (0, "poor", "good", None, "grand, dense")
    stored = panel.session.groups()
    assert (stored[1].representative, stored[1].usefulness, stored[1].qualifiers) == (None, 1, ["grand", "dense"])
    assert [e["action"] for e in study.events()].count("group") == 3


@pytest.fixture
def three(tmp_path):
    s = Study.create(tmp_path / "three.db", grammars={f"g{i}": lattice_picks(seed=i) for i in (1, 2, 3)})
    yield s
    s.close()


def test_a_double_click_on_finish_cannot_finish_the_next_grammar(three):
    panel = StudyPanel(three, three.add_participant(consent=True), thumb_size=32)
    assert panel.session.grammar == "g1" and "g1: 1 of 3" in panel.header.value
    panel.assign([range(1, 10), range(10, 19), range(19, 28)])
    for group in (1, 2, 3):
        panel.answer(group, representative=9 * group, usefulness="good", difference="fair", quality="good", qualifiers="x")
    panel.finish_button.click()
    panel.finish_button.click()  # the second click of a double click
    assert panel.message.kind == "info" and "thank you" in panel.message.text
    assert [(t["grammar"], t["finished_at"] is not None) for t in three.tests()] == [("g1", True)]
    assert panel.between in panel.widget.children and "Grammar 1 of 3 done" in panel.between.value
    assert panel.continue_button in panel.widget.children and panel.finish_button not in panel.widget.children
    panel.continue_button.click()
    panel.continue_button.click()  # a double click on Continue opens one test, once
    assert panel.session.grammar == "g2" and "g2: 2 of 3" in panel.header.value
    assert [(t["grammar"], t["finished_at"] is not None) for t in three.tests()] == [("g1", True), ("g2", False)]
    assert panel.grid in panel.widget.children and panel.session.groups() == []
    resumed = StudyPanel(three, panel.participant, thumb_size=32)  # a re-run cell resumes g2
    assert resumed.session.grammar == "g2"
