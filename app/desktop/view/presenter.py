"""What the 3D view shows of the explorer's state: the plant's colours, the selection, the cut preview.

:class:`PlantPresenter` turns the controller's snapshots into calls on the
:class:`~ramure.app.desktop.view.plant_view.PlantView`: the plant drawn with its base
colours, the selection red (or the kinship hues of one selected leaf), the leaves a regrow
would change orange, the selection's box and selected fruit.  It keeps what that drawing
needs between snapshots (the plant's base colours and fruit leaves, the preview it was
given, the version on screen) and asks its :class:`PlantSource` (the controller, which the
view room does not import) for the preview, the kinship colours and the selection's box.

It tells the window what the docks should show with signals: :attr:`~PlantPresenter.plant_shown`
once a new version's frame is on screen, :attr:`~PlantPresenter.selection_shown` when the
selection changed, :attr:`~PlantPresenter.cut_message` the preview's sentence.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol

import numpy as np

from PySide6.QtCore import QObject, Signal

from ramure.app.desktop import state
from ramure.errors import RamureError

if TYPE_CHECKING:
    from ramure.app.desktop.state import Snapshot
    from ramure.app.desktop.view.plant_view import PlantView

NO_LEAVES = np.zeros(0, np.int64)


class PlantSource(Protocol):
    """What the presenter reads from the explorer (the desktop's controller has it)."""

    @property
    def snapshot(self) -> Snapshot:
        """The model's last published state."""
        ...

    def preview(self, inline: bool = True) -> object:
        """The selection's cut preview ``(version, selection, rho, CutPreview or None)``, or a job."""
        ...

    def kinship_colors(self) -> np.ndarray | None:
        """Per-cell kinship RGB of the plant on screen, or None."""
        ...

    def selection_box(self) -> np.ndarray | None:
        """The selection's box as line segments, or None."""
        ...


class PlantPresenter(QObject):
    """Draws the source's snapshots in ``view``: colours, selection, cut preview, kinship."""

    #: A new plant version is on screen (its first frame drawn): the docks may follow.
    plant_shown = Signal(object)
    #: The selection was drawn and the docks' part of it should follow (the selection).
    selection_shown = Signal(object)
    #: The cut preview's sentence for the regeneration panel ("" while none is known).
    cut_message = Signal(str)

    def __init__(self, source: PlantSource, view: PlantView, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.source = source
        self.view = view
        #: Colour the plant by kinship to one selected leaf (the View menu's "Kinship colours").
        self.kinship = False
        #: The version drawn last (None before the first).
        self.drawn_version: int | None = None
        #: The current plant draws what the plant drawn before it drew (see MainWindow.after_regrow).
        self.same_as_before = False
        #: The cut preview: the (version, selection, rho) it was computed for, and its leaves (orange).
        self.preview_key: tuple | None = None
        self.cut_leaves: np.ndarray = NO_LEAVES
        self.base_colors: np.ndarray | None = None
        self.fruit_leaves: np.ndarray = NO_LEAVES

    def show_plant(self, snap: Snapshot, reset_camera: bool | None = None) -> None:
        """A new plant version: redraw the 3D view, then emit :attr:`plant_shown`.  The camera
        stays where it is on an edit; ``reset_camera`` None frames the plant again only when
        the derivation count changed (a plant of another size)."""
        shown = self.view.snapshot
        old = getattr(shown, "skeleton", None)  # compared after the frame (no copy)
        if reset_camera is None:
            reset_camera = shown is not None and shown.n != snap.n
        self.base_colors = state.base_colors(snap.mesh)
        self.fruit_leaves = state.fruit_leaves(snap.mesh)
        self.set_cut_preview(None)  # a new plant: the preview of the old one is gone
        self.view.show_plant(snap, self.plant_colors(snap.selection), reset_camera)
        self.drawn_version = snap.version
        if snap.selection:
            self.request_preview()  # e.g. the part a regrow kept selected
        self.show_selection(snap.selection, recolour=False, docks=False)
        # the edit's frame first (a draft for a large plant); the docks follow in the same turn
        self.view.redraw(now=True)
        self.same_as_before = old is not None and state.same_plant((old.start, old.end), snap.skeleton)
        self.plant_shown.emit(snap)

    def plant_colors(self, selection: Sequence[int]) -> np.ndarray:
        """Per-cell RGB of the shown plant: the selection red, or the kinship hues."""
        snap = self.source.snapshot
        return state.cell_colors(
            snap.mesh, selection, self._kinship_colors(selection), base=self.base_colors, cut=self._cut_for(snap, selection)
        )

    def _cut_for(self, snap: Snapshot, selection: Sequence[int]) -> np.ndarray:
        """The preview's leaves when they were computed for this plant, selection and ρ."""
        key = (snap.version, tuple(selection), snap.rho)
        return self.cut_leaves if self.preview_key == key else NO_LEAVES

    def request_preview(self) -> None:
        """Show the selection's cut preview: at once on a small plant, else when its job is done."""
        result = self.source.preview()
        if isinstance(result, tuple):
            self.set_cut_preview(result)

    def set_cut_preview(self, result: tuple | None) -> None:
        """Show a preview job's result ``(version, selection, rho, CutPreview)``: the leaves a regrow
        would change in orange, the sentence in :attr:`cut_message` (nothing for a stale one)."""
        snap = self.source.snapshot
        if result is None or result[3] is None:
            self.preview_key, self.cut_leaves = None, NO_LEAVES
            self.cut_message.emit("")
            return
        version, selection, rho, preview = result
        if (version, selection, rho) != (snap.version, tuple(snap.selection), snap.rho):
            return  # the selection or ρ changed since: a newer preview job follows
        self.preview_key, self.cut_leaves = (version, selection, rho), preview.leaves
        self.cut_message.emit(preview.message)
        if self.drawn_version == snap.version:
            self.show_selection(snap.selection, docks=False)

    def _kinship_colors(self, selection: Sequence[int]) -> np.ndarray | None:
        if self.kinship and len(selection) == 1:
            try:
                return self.source.kinship_colors()
            except RamureError:
                return None
        return None

    def set_kinship(self, on: bool) -> None:
        """Colour the selection's relatives (``on``) or the selection only."""
        self.kinship = bool(on)
        self.show_selection(self.source.snapshot.selection)

    def show_selection(self, selection: Sequence[int], recolour: bool = True, docks: bool = True) -> None:
        """Recolour the plant: the selection red (or kinship hues), its OBB as a red wireframe
        (``recolour`` False: the plant was just drawn in :meth:`plant_colors`); ``docks``: emit
        :attr:`selection_shown` for the panels' part too (a new version's frame comes first)."""
        snap = self.source.snapshot
        kin = self._kinship_colors(selection) if recolour or self.kinship else None
        if docks and tuple(selection) != (self.preview_key or (None, ()))[1]:
            self.cut_message.emit("")  # the selection changed: its preview is on its way
            if len(selection):
                self.request_preview()
        if recolour:
            cut = self._cut_for(snap, selection)
            self.view.set_colors(state.cell_colors(snap.mesh, selection, kin, base=self.base_colors, cut=cut))
        self.view.set_fruit_selection(selection)
        self.view.set_selected_segments(
            np.flatnonzero(state.leaf_mask(snap.segment_leaf, selection)) if len(selection) and kin is None else []
        )
        try:
            self.view.set_box_for(self.source.selection_box if selection else None, len(selection))
        except RamureError:
            self.view.set_box(None)
        if docks:
            self.selection_shown.emit(selection)

    def fruit_selected(self, selection: Sequence[int]) -> int:
        """How many of the plant's fruit leaves ``selection`` holds."""
        return int(np.isin(self.fruit_leaves, selection).sum())

    def rectangle_points(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The drawn plant's points on screen and their leaves, for a rubber-band selection:
        branches by their midpoints, leaves and fruit by their centres (None while the view
        shows an older version than the model's)."""
        snap = self.source.snapshot
        if self.drawn_version != snap.version:
            return None
        xy = self.view.project(np.concatenate([snap.midpoints, snap.organ_points]))
        return xy, np.concatenate([snap.segment_leaf, snap.organ_leaves])
