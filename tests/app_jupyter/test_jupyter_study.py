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


def to_test(panel):
    """Continue on the instructions and practice pages, as the participant does."""
    while panel.step.kind in ("instructions", "practice"):
        panel.page_button.click()
    return panel


def answer_page(panel, **answers):
    """Fill the page of questions (attention checks, demographics) and press Continue."""
    for key, value in answers.items():
        panel.fields[key].value = value
    panel.page_button.click()


@pytest.fixture
def panel(study):
    return to_test(StudyPanel(study, study.add_participant(consent=True), "honda", thumb_size=40))


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
    assert panel.session.finished and "saved" in panel.message.text
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
        panel = to_test(StudyPanel(study, study.add_participant(consent=True), "g", thumb_size=32))
        card = panel.grid.children[panel.session.order().index(2)]
        assert card.children[0].value == png
        other = panel.grid.children[panel.session.order().index(1)]
        assert "no picture" in other.children[0].value and "#1" not in other.children[0].value  # a placeholder, no pick id
        panel.assign({2: 4})
        page = panel.screen_html()  # the fallback output: what a notebook reopened without a kernel shows
        label = panel.session.labels()
        assert page.count("data:image/png") == 1 and f"{label[2]} · group 4" in page and f"{label[1]} · unsorted" in page


def test_without_consent_the_panel_asks_for_it_first(study):
    code = study.add_participant(consent=False)
    panel = StudyPanel(study, code, "honda")
    assert panel.step.kind == "consent" and not hasattr(panel, "session") and "Contact:" in panel.page_text.value
    panel.page_button.click()  # the box is not ticked
    assert panel.message.kind == "error" and not study.has_consent(code)
    with pytest.raises(StudyInputError, match="consent"):
        study.session(code, "honda")
    panel.agree.value = True
    panel.page_button.click()
    assert study.has_consent(code) and panel.step.kind == "instructions"


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
    panel = to_test(StudyPanel(three, three.add_participant(consent=True), thumb_size=32))
    assert panel.session.grammar == "g1" and "Set 1 of 3" in panel.header.value and "g1" not in panel.header.value
    panel.assign([range(1, 10), range(10, 19), range(19, 28)])
    for group in (1, 2, 3):
        panel.answer(group, representative=9 * group, usefulness="good", difference="fair", quality="good", qualifiers="x")
    panel.finish_button.click()
    panel.finish_button.click()  # the second click of a double click
    assert panel.message.kind == "info" and "saved" in panel.message.text
    assert [(t["grammar"], t["finished_at"] is not None) for t in three.tests()] == [("g1", True)]
    assert panel.between in panel.widget.children and "Set 1 of 3 done" in panel.between.value
    assert panel.continue_button in panel.widget.children and panel.finish_button not in panel.widget.children
    panel.continue_button.click()
    panel.continue_button.click()  # a double click on Continue opens one page, once
    answer_page(panel, attention_1="fair")  # the attention checks come after the first set
    assert panel.session.grammar == "g2" and "Set 2 of 3" in panel.header.value
    assert [(t["grammar"], t["finished_at"] is not None) for t in three.tests()] == [("g1", True), ("g2", False)]
    assert panel.grid in panel.widget.children and panel.session.groups() == []
    resumed = StudyPanel(three, panel.participant, thumb_size=32)  # a re-run cell resumes g2
    assert resumed.session.grammar == "g2"


# -- issue 38 §2-§3: the same instrument as the desktop -----------------------------------------
def widget_texts(widget):
    """Every text a participant reads in ``widget``'s tree (HTML, labels, buttons, placeholders)."""
    import ipywidgets as W

    found = []
    for key in ("value", "description", "placeholder", "tooltip"):
        value = getattr(widget, key, None)
        if isinstance(value, str) and not isinstance(widget, (W.Text, W.Dropdown)) or key == "placeholder":
            found.append(str(value or ""))
    if isinstance(widget, (W.ToggleButtons, W.Dropdown)):
        found += [str(o[0] if isinstance(o, tuple) else o) for o in widget.options]
    for child in getattr(widget, "children", ()):
        found += widget_texts(child)
    return found


def test_pages_speak_the_studys_words_without_jargon(three):
    from ramure.studies.design import jargon_in

    panel = to_test(StudyPanel(three, three.add_participant(consent=True), thumb_size=32))
    panel.assign([range(1, 28)])
    seen = widget_texts(panel.widget)
    assert [t for t in seen if jargon_in(t)] == [] and not any("g1" in t.split() for t in seen)
    config = three.config()
    assert config.questions["usefulness"] in " ".join(seen) and "Finish this set" in seen


def test_custom_likert_levels_are_shown_and_stored_as_1_to_4(tmp_path):
    from ramure.studies.design import config_from_data

    config = config_from_data({"likert": {"levels": ["not at all", "a little", "rather", "very"]}})
    with Study.create(tmp_path / "s.db", grammars={"g": lattice_picks(seed=1)}, config=config) as study:
        panel = to_test(StudyPanel(study, study.add_participant(consent=True), thumb_size=32))
        panel.assign([range(1, 28)])
        assert panel.forms[1].usefulness.options == ("not at all", "a little", "rather", "very")
        panel.answer(1, usefulness="rather", qualifiers="dense, taller")
        group = panel.session.groups()[0]
        assert group.usefulness == 3 and group.qualifiers == ["dense", "taller"]  # two words, as in the desktop
        assert {e["front_end"] for e in study.events() if e["grammar"]} == {"notebook"}


def test_the_second_participant_starts_with_another_set_and_groups_go_past_9(three):
    three.add_participant(consent=True)
    panel = to_test(StudyPanel(three, three.add_participant(consent=True), thumb_size=32))
    assert panel.session.grammar == "g2" and panel.grammars == ["g2", "g3", "g1"]
    panel.assign({i: i for i in range(1, 28)})  # 27 groups of one picture
    assert len(panel.session.groups()) == 27 and panel.message.kind != "error"


def test_a_spent_budget_names_the_skipped_sets_and_the_code(tmp_path):
    from ramure.studies.design import StudyConfig

    config = StudyConfig(attention_checks=(), demographics=(), completion_code="NB-3")
    grammars = {f"g{i}": lattice_picks(seed=i) for i in (1, 2)}
    with Study.create(tmp_path / "s.db", grammars=grammars, budget_minutes=0.0001, config=config) as study:
        panel = to_test(StudyPanel(study, study.add_participant(consent=True), thumb_size=32))
        panel.assign([range(1, 28)])
        panel.answer(1, representative=5, usefulness="good", difference="fair", quality="good", qualifiers="x")
        panel.finish()
        panel.continue_button.click()
        assert panel.step.kind == "done" and panel.step.skipped == ("g2",)
        assert "set 2 of 2 was not shown" in panel.page_text.value and "NB-3" in panel.page_text.value


def test_demographics_then_the_completion_code(study):
    panel = to_test(StudyPanel(study, study.add_participant(consent=True), thumb_size=32))
    panel.assign([range(1, 28)])
    panel.answer(1, representative=5, usefulness="good", difference="fair", quality="good", qualifiers="x")
    panel.finish()
    answer_page(panel, attention_1="fair")
    answer_page(panel, age="25-39")  # expertise left out: refused, nothing stored
    assert panel.message.kind == "error" and "demographics" not in study.participant_answers(panel.participant)
    answer_page(panel, expertise="quite")
    assert panel.step.kind == "done" and study.completion_code(panel.participant) in panel.page_text.value
    assert study.participant_answers(panel.participant)["demographics"] == {"age": "25-39", "expertise": "quite"}


def test_enlarge_shows_the_stored_picture_and_the_grid_holds_27(tmp_path):
    (tmp_path / "img.png").write_bytes(b"\x89PNG fake")
    picks = [Pick(p.id, p.variant, p.pca, p.params, str(tmp_path / "img.png")) for p in lattice_picks()]
    with Study.create(tmp_path / "s.db", grammars={"g": picks}) as study:
        panel = to_test(StudyPanel(study, study.add_participant(consent=True)))
        assert len(panel.grid.children) == 27 and "repeat(9" in panel.grid.layout.grid_template_columns
        assert panel.zoom_box.layout.display == "none"
        card = panel.grid.children[0]
        card.children[1].children[2].click()  # the enlarge button under the first picture
        first = panel.session.order()[0]
        assert panel.zoom_box.layout.display == "" and panel.zoom.value == b"\x89PNG fake"
        assert panel.session.labels()[first] in panel.zoom_label.value


def test_withdraw_from_the_panel(study):
    keep = study.add_participant(consent=True)
    panel = to_test(StudyPanel(study, study.add_participant(consent=True), "honda", thumb_size=32))
    panel.assign([range(1, 5)])
    panel.withdraw_button.click()
    assert panel.withdraw_buttons.layout.display == ""
    panel.withdraw_buttons.children[1].click()
    assert [p["code"] for p in study.participants()] == [keep] and "deleted" in panel.page_text.value


def test_the_practice_sort_comes_first_in_the_notebook_too(tmp_path):
    from ramure.studies.design import StudyConfig

    grammars = {f"g{i}": lattice_picks(seed=i) for i in (1, 2)}
    config = StudyConfig(practice_set="g2", attention_checks=(), demographics=())
    with Study.create(tmp_path / "s.db", grammars=grammars, config=config) as study:
        panel = to_test(StudyPanel(study, study.add_participant(consent=True), thumb_size=32))
        assert panel.session.grammar == "g2" and "Practice" in panel.header.value
        panel.assign([range(1, 28)])
        panel.answer(1, representative=5, usefulness="good", difference="fair", quality="good", qualifiers="x")
        panel.finish()
        assert "Practice done" in panel.between.value
        panel.continue_button.click()
        assert panel.session.grammar == "g1" and "Set 1 of 1" in panel.header.value
