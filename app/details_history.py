"""Natural details kept in the session (issue 18): record what was grown, grow the last one again.

Lichen on a fruit, a crack on a fruit and lichen on the bark are recorded as the session's
data-only ``detail`` edits (:meth:`ramure.lsys.regeneration.regen.Session.add_detail`) with the settings
that made them: they are undone and redone with the other edits and saved in the session
file. Every detail is seeded, so growing it again from its settings gives the same result;
a front end shows the session's last detail after an undo, a redo or a load.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ramure.errors import ValueRefused

if TYPE_CHECKING:
    from ramure.app.model import Explorer


def selected_fruit(ex: Explorer) -> int:
    """The history leaf of the first selected fruit (what the fruit details act on)."""
    fruit = set(ex.fruit_ids())
    chosen = [leaf for leaf in ex.selection if leaf in fruit]
    if not chosen:
        raise ValueRefused("select a fruit first (click one): lichen and cracks grow on its closed surface")
    return int(chosen[0])


def record(ex: Explorer, kind: str, settings: dict, leaf: int | None = None) -> dict:
    """Record a grown detail as the session's newest edit; returns the edit."""
    ex.session.add_detail(kind, settings, [] if leaf is None else [int(leaf)])
    return ex.session.edits[-1]


def last_detail(ex: Explorer) -> dict | None:
    """The session's newest detail still on the plant (None: none)."""
    details = ex.session.details()
    return details[-1] if details else None


def grow_again(ex: Explorer, detail: dict) -> dict:
    """The result of a recorded detail, grown again from its settings (see :mod:`ramure.app.details`)."""
    from ramure.app.details import crack_on_fruit, lichen_on_fruit, lichen_on_surface, plant_bark

    s = detail["settings"]
    if detail["kind"] == "bark":
        poly, mesh = plant_bark(ex.skeleton)
        return lichen_on_surface(poly, mesh, s["clusters"], s["particles"], s["habit"], s["seed"])
    before = list(ex.selection)
    ex.select(list(detail["leaves"]))  # the fruit it was grown on
    try:
        if detail["kind"] == "lichen":
            adhesion = None if s.get("adhesion") is None else np.asarray(s["adhesion"], np.float64)
            return lichen_on_fruit(ex, s["clusters"], s["particles"], s["habit"], s["seed"], adhesion)
        anchor = None if s.get("anchor") is None else tuple(s["anchor"])
        return crack_on_fruit(ex, s["nodes"], s["seed"], anchor)
    finally:
        ex.select(before)
