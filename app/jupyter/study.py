"""Study mode in the notebook: one participant's tests, one grammar at a time.

:class:`StudyPanel` drives a :class:`ramure.studies.TestSession`, so every answer is
checked and stored in the study's SQLite file as it is given (one
transaction each, timed).  The participant

1. sorts the 27 thumbnails (in their own seeded order) by giving each a
   group number,
2. for each group chooses a representative, rates usefulness, difference and
   the representative (poor / fair / good / excellent) and names it with one
   or more qualifiers,
3. presses *Finish*; anything missing is listed instead.  Between two grammars a
   short page ("Grammar 1 of 3 done", *Continue*) stops a double click on *Finish*
   from reaching the next test; the header shows "N of M".

The same steps are methods (:meth:`~StudyPanel.assign`, :meth:`~StudyPanel.answer`,
:meth:`~StudyPanel.finish`) that set the widgets and run their handlers.

>>> import tempfile, pathlib
>>> from ramure.studies import Study, lattice_picks
>>> study = Study.create(pathlib.Path(tempfile.mkdtemp()) / "s.db", grammars={"honda": lattice_picks()})
>>> panel = StudyPanel(study, study.add_participant(consent=True), "honda")
>>> panel.assign({i: 1 if i <= 13 else 2 for i in range(1, 28)})
>>> [len(g.images) for g in panel.session.groups()]
[13, 14]
>>> panel.finish() is None, panel.message.text.startswith("the test is not complete")
(True, True)
>>> study.close()
"""

from __future__ import annotations

import pathlib
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, TypeVar

import ipywidgets as W

from ramure.app.jupyter._ui import Fallback, MessageLine, button, observe, png_image, png_tag
from ramure.errors import RamureError
from ramure.studies.likert import LEVELS

if TYPE_CHECKING:
    from ramure.studies import Study
    from ramure.studies.session import Group

T = TypeVar("T")

MAX_GROUPS = 9


def _thumbnail(pick, size):
    path = pathlib.Path(pick.image) if pick.image else None
    if path is not None and path.is_file():
        return png_image(path.read_bytes(), width=size)
    return W.HTML(
        f"<div style='width:{size}px;height:{size}px;background:#eceff1;display:flex;"
        f"align-items:center;justify-content:center;color:#607d8b;font-size:20px'>no picture</div>"
    )


def _likert(description):
    return W.ToggleButtons(
        options=LEVELS, value=None, description=description, style={"description_width": "110px", "button_width": "72px"}
    )


class GroupQuestions:
    """The questionnaire of one stored group (representative, three ratings, qualifiers)."""

    def __init__(self, panel: StudyPanel, group: Group, number: int | None = None) -> None:
        self.panel = panel
        self.label = group.label  # as stored (1, 2, ... in group-number order)
        self.number = group.label if number is None else number  # as the participant numbered it
        several = len(group.images) > 1
        labels, shown = panel.session.labels(), panel.session.in_order(group.images)  # never pick ids: they encode the lattice
        # 0 stands for "not chosen yet": a Dropdown whose value is None shows a blank box
        self.representative = W.Dropdown(
            options=[("choose…", 0)] + [(labels[i], i) for i in shown],
            value=(group.representative or 0) if several else 0,
            description="representative",
            style={"description_width": "110px"},
            layout=W.Layout(width="240px", display="" if several else "none"),
        )
        self.usefulness = _likert("usefulness")
        self.difference = _likert("difference")
        self.quality = _likert("representative")
        self.quality.layout.display = "" if several else "none"
        for widget, stored in (
            (self.usefulness, group.usefulness),
            (self.difference, group.difference),
            (self.quality, group.representative_quality),
        ):
            widget.value = LEVELS[stored - 1] if stored else None
        self.qualifiers = W.Text(
            value=", ".join(group.qualifiers),
            description="qualifiers",
            placeholder="e.g. petit, dense",
            continuous_update=False,
            style={"description_width": "110px"},
            layout=W.Layout(width="420px"),
        )
        observe(self.representative, lambda ch: self._save("representative", ch["new"]))
        observe(self.usefulness, lambda ch: self._save("usefulness", ch["new"]))
        observe(self.difference, lambda ch: self._save("difference", ch["new"]))
        observe(self.quality, lambda ch: self._save("quality", ch["new"]))
        observe(self.qualifiers, lambda ch: self._save("qualifiers", ch["new"]))
        self.widget = W.VBox(
            [
                W.HTML(f"<b>Group {self.number}</b>: pictures {', '.join(labels[i] for i in shown)}"),
                self.representative,
                self.usefulness,
                self.difference,
                self.quality,
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
            widget.value = LEVELS[stored - 1] if stored else None
        self.qualifiers.value = ", ".join(group.qualifiers)

    def _save(self, what, value) -> None:
        if self.panel.quiet or value is None or (what == "representative" and value == 0):
            return
        s, g = self.panel.session, self.label
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
        wanted = [t.strip() for t in str(text).split(",") if t.strip()]
        stored = next(g.qualifiers for g in self.panel.session.groups() if g.label == self.label)
        for name in stored:
            if name not in wanted:
                self.panel.session.remove_qualifier(self.label, name)
        for name in wanted:
            if name not in stored:
                self.panel.session.add_qualifier(self.label, name)


class StudyPanel:
    """A participant's tests of an open :class:`ramure.studies.Study`, one grammar at a time.

    ``grammar`` is one grammar name, a list of them, or None for all the study's
    grammars, in order; the panel opens the first whose test is unfinished.  After
    each finished test but the last a short page says "Grammar 1 of 3 done" with a
    *Continue* button, so a double click on *Finish* never reaches the next test.
    """

    def __init__(self, study: Study, participant: str, grammar: str | Sequence[str] | None = None, thumb_size: int = 96) -> None:
        self.study = study
        self.participant = participant
        self.grammars = [grammar] if isinstance(grammar, str) else list(grammar or study.grammars)
        self.quiet = False
        self.message = MessageLine()
        self.header = W.HTML()
        self._thumb_size = thumb_size
        self.between = W.HTML()
        self.continue_button = button("Continue", self.next_test, style="primary", tooltip="start the next grammar")
        self.widget = W.VBox()
        unfinished = [g for g in self.grammars if not self._finished(g)]
        self.open(unfinished[0] if unfinished else self.grammars[-1])

    def _finished(self, grammar: str) -> bool:
        return self.study.finished(self.participant, grammar)

    def progress(self) -> tuple[int, int]:
        """``(n, m)``: the open test is grammar n of the participant's m."""
        return self.grammars.index(self.session.grammar) + 1, len(self.grammars)

    def open(self, grammar: str) -> None:
        """Start, or resume, the test on ``grammar`` (refused without consent or budget)."""
        self.session = self.study.session(self.participant, grammar)
        picks = {p.id: p for p in self.session.picks()}
        self.group_of = {}
        self._picks = picks
        thumb_size = self._thumb_size
        cards = []
        options = [("–", 0)] + [(str(g), g) for g in range(1, MAX_GROUPS + 1)]
        labels = self.session.labels()
        for image in self.session.order():
            dropdown = W.Dropdown(options=options, value=0, layout=W.Layout(width="52px"))
            observe(dropdown, lambda ch: None if self.quiet else self.run(self._store_groups))
            self.group_of[image] = dropdown
            cards.append(
                W.VBox(
                    [
                        _thumbnail(picks[image], thumb_size),
                        W.HBox([W.Label(labels[image], layout=W.Layout(width="38px")), dropdown]),
                    ]
                )
            )
        self.grid = W.GridBox(cards, layout=W.Layout(grid_template_columns=f"repeat(9, {thumb_size + 8}px)"))
        self.questions = W.VBox()
        self.forms: dict[int, GroupQuestions] = {}
        self._layout: list[tuple[int, tuple]] | None = None
        self.finish_button = button(
            "Finish test", self.finish, style="primary", tooltip="store the test as finished (refused while answers are missing)"
        )
        self.todo = W.HTML()
        self.widget.children = [
            self.header,
            self.message.widget,
            W.HTML(
                "<b>1. Sort the trees</b>: give each image a group number; trees in a group look "
                "alike, groups look different (a group may hold one image)."
            ),
            self.grid,
            W.HTML(
                "<b>2. For each group</b>: choose a representative, rate, and name it (several qualifiers separated by commas)."
            ),
            self.questions,
            W.HBox([self.finish_button]),
            self.todo,
        ]
        self.refresh()

    def next_test(self) -> None:
        """Continue: open the next grammar whose test is unfinished (from the page between tests)."""
        if self.widget.children[-1] is not self.continue_button:
            return
        left = [g for g in self.grammars if not self._finished(g)]
        if left:
            self.run(lambda: self.open(left[0]))

    def _show_between(self) -> None:
        n, m = self.progress()
        self.between.value = f"<h3>Grammar {n} of {m} done</h3><p>Your answers are saved.</p>"
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
            self.message.show("test finished and stored — thank you", "info")
            if any(not self._finished(g) for g in self.grammars):
                self._show_between()

    # -- display -------------------------------------------------------------
    def _ipython_display_(self) -> None:
        """The test widget, then a static picture of it (for a notebook reopened without a kernel)."""
        s = self.session
        text = (
            f"<StudyPanel: participant {s.participant}, grammar {s.grammar}, "
            f"{len(s.groups())} groups, {'finished' if s.finished else 'in progress'}>"
        )
        Fallback(self.widget, lambda: (self.screen_html(), None), text)._ipython_display_()

    def screen_html(self) -> str:
        """The participant's images in their order, each with its group (a static picture of the test)."""
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
        s = self.session
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
        n, m = self.progress()
        self.header.value = (
            f"<h3 style='margin:4px 0'>Study “{self.study.name}” — participant {s.participant}, "
            f"grammar {s.grammar}: {n} of {m} ({state})</h3>"
        )
        todo = [] if s.finished else s.missing()
        self.todo.value = (
            ("<small>still to do: " + "; ".join(todo[:8]) + ("…" if len(todo) > 8 else "") + "</small>") if todo else ""
        )
        self.finish_button.disabled = s.finished
        if s.finished:
            for form in self.forms.values():
                for child in form.widget.children[1:]:
                    child.disabled = True
