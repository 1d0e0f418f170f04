"""Study mode in the notebook: one participant's pages, one picture set at a time.

:class:`StudyPanel` shows the pages of a :class:`ramure.studies.design.ParticipantFlow`
with the study's own words (the same as the desktop's: consent with contact and data
retention, instructions, practice, attention checks, demographics, the completion code)
and drives a :class:`ramure.studies.TestSession`, so every answer is checked and stored in
the study's SQLite file as it is given (one transaction each, timed, marked "notebook").
For each set, in the participant's Latin-square order, the participant

1. sorts the 27 pictures (in their own seeded order, all in view; *enlarge* shows one
   large) by giving each a group number,
2. for each group chooses the picture that stands for it, answers the study's three
   Likert questions and describes it in words (split at commas, as everywhere),
3. presses *Finish*; anything missing is listed instead.  Between two sets a
   short page ("Set 1 of 3 done", *Continue*) stops a double click on *Finish*
   from reaching the next test; the header shows "Set N of M".

The same steps are methods (:meth:`~StudyPanel.assign`, :meth:`~StudyPanel.answer`,
:meth:`~StudyPanel.finish`) that set the widgets and run their handlers.

>>> import tempfile, pathlib
>>> from ramure.studies import Study, lattice_picks
>>> study = Study.create(pathlib.Path(tempfile.mkdtemp()) / "s.db", grammars={"honda": lattice_picks()})
>>> panel = StudyPanel(study, study.add_participant(consent=True), "honda")
>>> panel.step.kind
'instructions'
>>> panel.page_button.click(); panel.page_button.click()  # the instructions, then the practice page
>>> panel.assign({i: 1 if i <= 13 else 2 for i in range(1, 28)})
>>> [len(g.images) for g in panel.session.groups()]
[13, 14]
>>> panel.finish() is None, panel.message.text.startswith("the test is not complete")
(True, True)
>>> study.close()
"""

from __future__ import annotations

import html
import pathlib
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, TypeVar

import ipywidgets as W

from ramure.app.jupyter._ui import Fallback, MessageLine, button, observe, png_image, png_tag
from ramure.errors import RamureError
from ramure.studies.design import WORDS, ParticipantFlow, Question, Step, set_title, split_words

if TYPE_CHECKING:
    from ramure.studies import Study
    from ramure.studies.session import Group, TestSession

T = TypeVar("T")

#: A group number per picture: as many groups as pictures (the desktop has no limit either).
MAX_GROUPS = 27


def _thumbnail(pick, size):
    path = pathlib.Path(pick.image) if pick.image else None
    if path is not None and path.is_file():
        image = png_image(path.read_bytes(), width=size)
        image.layout.width, image.layout.max_width = "100%", f"{size}px"
        return image
    return W.HTML(
        f"<div style='width:{size}px;height:{size}px;background:#eceff1;display:flex;"
        f"align-items:center;justify-content:center;color:#607d8b;font-size:20px'>no picture</div>"
    )


def _likert(levels):
    return W.ToggleButtons(options=list(levels), value=None, style={"button_width": "88px"})


def _page_html(title: str, text: str) -> str:
    """A page's title and the study's plain text (paragraphs at blank lines), escaped."""
    paragraphs = "".join(f"<p>{html.escape(p)}</p>" for p in text.split("\n\n") if p.strip())
    return f"<h3>{html.escape(title)}</h3>{paragraphs}"


class GroupQuestions:
    """The questionnaire of one stored group (representative, three ratings, qualifiers)."""

    def __init__(self, panel: StudyPanel, group: Group, number: int | None = None) -> None:
        self.panel = panel
        self.levels = panel.config.levels
        self.label = group.label  # as stored (1, 2, ... in group-number order)
        self.number = group.label if number is None else number  # as the participant numbered it
        several = len(group.images) > 1
        labels, shown = panel.session.labels(), panel.session.in_order(group.images)  # never pick ids: they encode the lattice
        # 0 stands for "not chosen yet": a Dropdown whose value is None shows a blank box
        self.representative = W.Dropdown(
            options=[("choose…", 0)] + [(labels[i], i) for i in shown],
            value=(group.representative or 0) if several else 0,
            layout=W.Layout(width="120px", display="" if several else "none"),
        )
        questions = panel.config.questions
        self.usefulness = _likert(self.levels)
        self.difference = _likert(self.levels)
        self.quality = _likert(self.levels)
        self.quality.layout.display = "" if several else "none"
        for widget, stored in (
            (self.usefulness, group.usefulness),
            (self.difference, group.difference),
            (self.quality, group.representative_quality),
        ):
            widget.value = self.levels[stored - 1] if stored else None
        self.qualifiers = W.Text(
            value=", ".join(group.qualifiers),
            placeholder=WORDS["words_hint"],
            continuous_update=False,
            layout=W.Layout(width="520px"),
        )
        observe(self.representative, lambda ch: self._save("representative", ch["new"]))
        observe(self.usefulness, lambda ch: self._save("usefulness", ch["new"]))
        observe(self.difference, lambda ch: self._save("difference", ch["new"]))
        observe(self.quality, lambda ch: self._save("quality", ch["new"]))
        observe(self.qualifiers, lambda ch: self._save("qualifiers", ch["new"]))
        self.widget = W.VBox(
            [
                W.HTML(f"<b>{WORDS['group']} {self.number}</b>: pictures {', '.join(labels[i] for i in shown)}"),
                W.HBox(
                    [W.Label(WORDS["representative"]), self.representative], layout=W.Layout(display="" if several else "none")
                ),
                W.HTML(html.escape(questions["usefulness"])),
                self.usefulness,
                W.HTML(html.escape(questions["difference"])),
                self.difference,
                W.HTML(html.escape(questions["representative"]), layout=W.Layout(display="" if several else "none")),
                self.quality,
                W.HTML(html.escape(WORDS["words"])),
                self.qualifiers,
            ],
            layout=W.Layout(border="1px solid #ddd", padding="4px", margin="2px 0"),
        )

    def update(self, group: Group) -> None:
        """Show the stored answers of ``group`` (also undoes a refused answer on screen)."""
        if len(group.images) > 1:
            self.representative.value = group.representative or 0
        for widget, stored in (
            (self.usefulness, group.usefulness),
            (self.difference, group.difference),
            (self.quality, group.representative_quality),
        ):
            widget.value = self.levels[stored - 1] if stored else None
        self.qualifiers.value = ", ".join(group.qualifiers)

    def _save(self, what, value) -> None:
        if self.panel.quiet or value is None or (what == "representative" and value == 0):
            return
        s, g = self.panel.session, self.label
        if what in ("usefulness", "difference", "quality"):
            value = self.levels.index(value) + 1  # the study's level names, stored as 1-4
        if what == "representative":
            self.panel.run(lambda: s.set_representative(g, value))
        elif what == "usefulness":
            self.panel.run(lambda: s.rate(g, usefulness=value))
        elif what == "difference":
            self.panel.run(lambda: s.rate(g, difference=value))
        elif what == "quality":
            self.panel.run(lambda: s.rate(g, representative=value))
        else:
            self.panel.run(lambda: self._sync_qualifiers(value))

    def _sync_qualifiers(self, text) -> None:
        wanted = split_words(text)
        stored = next(g.qualifiers for g in self.panel.session.groups() if g.label == self.label)
        for name in stored:
            if name not in wanted:
                self.panel.session.remove_qualifier(self.label, name)
        for name in wanted:
            if name not in stored:
                self.panel.session.add_qualifier(self.label, name)


class StudyPanel:
    """A participant's pages on an open :class:`ramure.studies.Study` (see the module docstring).

    ``grammar`` is one grammar name, a list of them, or None for all the study's
    grammars in the participant's Latin-square order; the panel shows the page the
    :class:`~ramure.studies.design.ParticipantFlow` says comes next (consent, instructions,
    practice, a set, questions, the last page).  After each finished set but the last a
    short page says "Set 1 of 3 done" with a *Continue* button, so a double click on
    *Finish* never reaches the next test.
    """

    def __init__(self, study: Study, participant: str, grammar: str | Sequence[str] | None = None, thumb_size: int = 110) -> None:
        self.study = study
        self.participant = participant
        self.flow = ParticipantFlow(study, participant, front_end="notebook")
        self.config = self.flow.config
        self.grammars = [grammar] if isinstance(grammar, str) else list(grammar or self.flow.grammars)
        self.quiet = False
        self.message = MessageLine()
        self.header = W.HTML()
        self._thumb_size = thumb_size
        self.between = W.HTML()
        self.continue_button = button("Continue", self.next_test, style="primary", tooltip="go on")
        self.page_text = W.HTML()
        self.page_button = button("Continue", self._page_done, style="primary")
        self.agree = W.Checkbox(description="I have read this and I agree to take part.", indent=False)
        self.fields: dict[str, W.Dropdown | W.Text] = {}
        self.zoom = png_image()
        self.zoom_label = W.HTML()
        self.zoom_box = W.VBox(
            [self.zoom_label, self.zoom, button("Close", self._unzoom)], layout=W.Layout(display="none", align_items="center")
        )
        self.withdraw_buttons = W.HBox(
            [
                button("Withdraw", lambda: self.withdraw(False), tooltip="your answers will not be used"),
                button("Withdraw and delete my answers", lambda: self.withdraw(True), style="danger"),
            ],
            layout=W.Layout(display="none"),
        )
        self.withdraw_button = button("Withdraw from the study…", self._ask_withdraw)
        self.session: TestSession  # set by open(), when a set is shown
        self.widget = W.VBox()
        self.show_step()

    def _finished(self, grammar: str) -> bool:
        return self.study.finished(self.participant, grammar)

    def progress(self) -> tuple[int, int]:
        """``(n, m)``: the open test is set n of the participant's m (n 0: the practice set)."""
        grammar = self.session.grammar
        return (self.grammars.index(grammar) + 1 if grammar in self.grammars else 0), len(self.grammars)

    def title(self) -> str:
        """ "Set n of m", or "Practice", for the open test."""
        n, m = self.progress()
        return set_title(n, m) if n else "Practice"

    # -- pages ---------------------------------------------------------------------------
    def show_step(self) -> Step:
        """Show the page the flow says comes next (sets outside ``grammars`` are not this panel's)."""
        step = self.flow.step()
        if step.kind == "test":
            left = [g for g in self.grammars if not self._finished(g)]
            practice = step.grammar is not None and step.grammar == self.config.practice_set
            grammar = step.grammar if practice or step.grammar in left else (left[0] if left else None)
            if grammar is not None:
                self.step = Step("test", step.title, grammar=grammar)
                self.open(grammar)
                return self.step
            step = Step("done", "Thank you", WORDS["saved"])  # the sets of this panel are done
        self.step = step
        body: list[W.Widget] = [self.message.widget, self.page_text]
        self.page_text.value = _page_html(step.title, step.text)
        self.header.value = ""
        if step.kind == "consent":
            self.agree.value = False
            body += [self.agree, self.page_button]
        elif step.kind in ("instructions", "practice"):
            body.append(self.page_button)
        elif step.kind in ("attention", "demographics"):
            self.fields = {q.key: self._field(q) for q in step.questions}
            body += [W.VBox([W.HTML(html.escape(q.text)), self.fields[q.key]]) for q in step.questions]
            body.append(self.page_button)
        if step.kind != "done":
            body += [self.withdraw_button, self.withdraw_buttons]
        self.widget.children = body
        return step

    @staticmethod
    def _field(question: Question) -> W.Dropdown | W.Text:
        if question.options:
            return W.Dropdown(options=["", *question.options], value="", layout=W.Layout(width="320px"))
        return W.Text(layout=W.Layout(width="320px"))

    def _page_done(self) -> None:
        """Continue on the consent, instructions, practice or questions page."""
        kind = self.step.kind
        if kind == "consent" and not self.agree.value:
            self.message.show("please tick the box to agree first", "error")
            return
        try:
            if kind == "consent":
                self.flow.consent()
            elif kind in ("instructions", "practice"):
                self.flow.acknowledge(kind)
            elif kind in ("attention", "demographics"):
                self.flow.answer(kind, {k: str(f.value or "") for k, f in self.fields.items()})
            else:
                return
        except RamureError as err:
            self.message.show(err, "error")
            return
        self.message.clear()
        self.show_step()

    def enlarge(self, image: int) -> None:
        """Show picture ``image`` large above the others (the *enlarge* button under it)."""
        path = pathlib.Path(self._picks[image].image or "")
        self.zoom.value = path.read_bytes() if path.is_file() else b""
        self.zoom.layout.width = "min(480px, 90%)"
        self.zoom_label.value = f"<b>{html.escape(self.session.labels()[image])}</b>"
        self.zoom_box.layout.display = ""

    def _unzoom(self) -> None:
        self.zoom_box.layout.display = "none"

    def _ask_withdraw(self) -> None:
        self.withdraw_buttons.layout.display = ""

    def withdraw(self, delete: bool) -> None:
        """The participant withdraws: left out of the analysis, or (``delete``) erased."""
        try:
            self.study.withdraw(self.participant, delete=delete)
        except RamureError as err:
            self.message.show(err, "error")
            return
        done = "Your answers are deleted." if delete else "Your answers will not be used."
        self.page_text.value = _page_html("You have withdrawn", f"Thank you. {done}")
        self.header.value = ""
        self.widget.children = [self.page_text]

    def open(self, grammar: str) -> None:
        """Start, or resume, the test on ``grammar`` (refused without consent or budget)."""
        self.session = self.flow.session(grammar)
        picks = {p.id: p for p in self.session.picks()}
        self.group_of = {}
        self._picks = picks
        thumb_size = self._thumb_size
        cards = []
        options = [("–", 0)] + [(str(g), g) for g in range(1, MAX_GROUPS + 1)]
        labels = self.session.labels()
        for image in self.session.order():
            dropdown = W.Dropdown(options=options, value=0, layout=W.Layout(width="56px"))
            observe(dropdown, lambda ch: None if self.quiet else self.run(self._store_groups))
            self.group_of[image] = dropdown
            zoom = button("", lambda image=image: self.enlarge(image), tooltip="see it larger", icon="search-plus", width="32px")
            cards.append(
                W.VBox(
                    [
                        _thumbnail(picks[image], thumb_size),
                        W.HBox([W.Label(labels[image], layout=W.Layout(width="30px")), dropdown, zoom]),
                    ],
                    layout=W.Layout(min_width="0"),
                )
            )
        self.grid = W.GridBox(  # 9 columns sharing the width: the 27 pictures in 3 rows, all in view
            cards, layout=W.Layout(grid_template_columns="repeat(9, minmax(0, 1fr))", grid_gap="2px", max_width="1200px")
        )
        self.questions = W.VBox()
        self.forms: dict[int, GroupQuestions] = {}
        self._layout: list[tuple[int, tuple]] | None = None
        self.finish_button = button(
            WORDS["finish"],
            self.finish,
            style="primary",
            tooltip="store this set as finished (refused while answers are missing)",
        )
        self.todo = W.HTML()
        self.widget.children = [
            self.header,
            self.message.widget,
            W.HTML(f"<b>1.</b> {html.escape(WORDS['sort'])}"),
            self.zoom_box,
            self.grid,
            W.HTML(f"<b>2.</b> {html.escape(WORDS['answer'])}"),
            self.questions,
            W.HBox([self.finish_button]),
            self.todo,
            self.withdraw_button,
            self.withdraw_buttons,
        ]
        self.refresh()

    def next_test(self) -> None:
        """Continue: the page after a finished set (the next set, or questions, or the last page)."""
        if self.continue_button not in self.widget.children:
            return
        try:
            self.show_step()
        except RamureError as err:
            self.message.show(err, "error")

    def _show_between(self) -> None:
        self.between.value = f"<h3>{self.title()} done</h3><p>{WORDS['saved']}</p>"
        self.header.value = ""
        self.widget.children = [self.message.widget, self.between, self.continue_button]

    # -- actions -------------------------------------------------------------
    def run(self, action: Callable[[], T]) -> T | None:
        """Run ``action()``; a refused answer is shown inline (nothing stored changes)."""
        try:
            result = action()
        except RamureError as err:
            self.message.show(err, "error")
            self.refresh()
            return None
        self.message.clear()
        self.refresh()
        return result

    def numbers(self) -> list:
        """The group numbers in use on screen, in order (stored as groups 1, 2, ...)."""
        return sorted({d.value for d in self.group_of.values() if d.value})

    def images_of(self, number: int) -> list:
        """The images the participant put in group ``number``, sorted."""
        return sorted(image for image, d in self.group_of.items() if d.value == number)

    def _store_groups(self) -> None:
        self.session.set_groups([self.images_of(n) for n in self.numbers()])

    def assign(self, groups: Mapping[int, int] | Iterable[Iterable[int]]) -> None:
        """Set every image's group at once: ``{image: group}`` or a list of groups of images
        (images left out stay unsorted), then store the grouping."""
        table = (
            dict(groups)
            if isinstance(groups, Mapping)
            else {image: label for label, images in enumerate(groups, start=1) for image in images}
        )
        self.quiet = True
        try:
            for image, dropdown in self.group_of.items():
                dropdown.value = int(table.get(image, 0))
        except Exception as exc:  # noqa: BLE001 - a group number outside the drop-down
            self.quiet = False
            self.message.show(f"group numbers must be 1-{MAX_GROUPS} ({exc})", "error")
            return
        finally:
            self.quiet = False
        self.run(self._store_groups)

    def answer(
        self,
        group: int,
        representative: int | None = None,
        usefulness: str | None = None,
        difference: str | None = None,
        quality: str | None = None,
        qualifiers: str | Iterable[str] | None = None,
    ) -> None:
        """Answer for ``group`` (its number on screen) as the participant would, through its widgets."""
        form = self.forms.get(group)
        if form is None:
            self.message.show(f"group {group} does not exist (sort the images first)", "error")
            return
        for widget, value in (
            (form.representative, representative),
            (form.usefulness, usefulness),
            (form.difference, difference),
            (form.quality, quality),
        ):
            if value is not None:
                widget.value = value
        if qualifiers is not None:
            form.qualifiers.value = qualifiers if isinstance(qualifiers, str) else ", ".join(qualifiers)

    def finish(self) -> None:
        """Finish the test; refused, listing what is missing, while it is incomplete.

        A second click on a finished test does nothing (it never reaches the next one).
        """
        if self.session.finished:
            return
        self.run(self.session.finish)
        if self.session.finished:
            self.message.show(f"{WORDS['saved']} Thank you.", "info")
            if any(not self._finished(g) for g in self.grammars):
                self._show_between()
            else:
                self.show_step()

    # -- display -------------------------------------------------------------
    def _ipython_display_(self) -> None:
        """The test widget, then a static picture of it (for a notebook reopened without a kernel)."""
        s = getattr(self, "session", None)
        text = (
            f"<StudyPanel: participant {self.participant}, page {self.step.kind}>"
            if s is None
            else f"<StudyPanel: participant {s.participant}, grammar {s.grammar}, "
            f"{len(s.groups())} groups, {'finished' if s.finished else 'in progress'}>"
        )
        Fallback(self.widget, lambda: (self.screen_html(), None), text)._ipython_display_()

    def screen_html(self) -> str:
        """The participant's images in their order, each with its group (a static picture of the test)."""
        if getattr(self, "session", None) is None or self.step.kind != "test":
            return self.page_text.value
        cells = []
        labels = self.session.labels()
        for image, dropdown in self.group_of.items():
            path = pathlib.Path(self._picks[image].image or "")
            picture = (
                png_tag(path.read_bytes(), self._thumb_size, labels[image])
                if path.is_file()
                else f"<div style='width:{self._thumb_size}px'>{labels[image]}</div>"
            )
            group = f"group {dropdown.value}" if dropdown.value else "unsorted"
            cells.append(
                f"<figure style='margin:2px;text-align:center'>{picture}"
                f"<figcaption style='font-size:11px'>{labels[image]} · {group}</figcaption></figure>"
            )
        return (
            f"{self.header.value}<div style='display:grid;grid-template-columns:repeat(9,"
            f"{self._thumb_size + 8}px)'>{''.join(cells)}</div>"
        )

    def refresh(self) -> None:
        """Show the stored groups and the session's state (resuming, or after a change the screen does not show
        yet) and enable what can be done now.
        """
        s = getattr(self, "session", None)
        if s is None or self.step.kind != "test":
            return
        groups = s.groups()
        self.quiet = True
        try:
            numbers = self.numbers()
            if [tuple(g.images) for g in groups] != [tuple(self.images_of(n)) for n in numbers]:
                # resuming, or the screen differs from what is stored: show the stored groups
                label_of = {image: g.label for g in groups for image in g.images}
                for image, dropdown in self.group_of.items():
                    dropdown.value = label_of.get(image, 0)
                numbers = self.numbers()
            for dropdown in self.group_of.values():
                dropdown.disabled = s.finished
            layout = [(n, tuple(g.images)) for n, g in zip(numbers, groups)]
            if layout != self._layout:  # the grouping changed: a new questionnaire
                self.forms = {n: GroupQuestions(self, g, n) for n, g in zip(numbers, groups)}
                self.questions.children = [f.widget for f in self.forms.values()]
                self._layout = layout
            else:
                for n, g in zip(numbers, groups):
                    self.forms[n].update(g)
        finally:
            self.quiet = False
        minutes = s.remaining_seconds() / 60
        state = "finished" if s.finished else f"{minutes:.0f} min left"
        self.header.value = (
            f"<h3 style='margin:4px 0'>{html.escape(self.config.title)} — participant {s.participant}: "
            f"{self.title()} ({state})</h3>"
        )
        todo = [] if s.finished else s.missing()
        self.todo.value = (
            ("<small>still to do: " + "; ".join(todo[:8]) + ("…" if len(todo) > 8 else "") + "</small>") if todo else ""
        )
        self.finish_button.disabled = s.finished
        if s.finished:
            for form in self.forms.values():
                for child in (form.representative, form.usefulness, form.difference, form.quality, form.qualifiers):
                    child.disabled = True
