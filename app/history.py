"""One undo history for the explorer: grammar text, constants, n, seed and plant edits.

:class:`~ramure.app.model.Explorer` keeps one :class:`Timeline` (both front ends undo
through it).

The model's :class:`~ramure.lsys.regen.Session` keeps the plant edits
(regrow, prune, constants, fruit) with their own undo and redo.  Changing the
grammar text, the derivation count or the seed starts a new session; this
module keeps the sessions left behind, so Undo walks back through them too.

:class:`Timeline` holds two stacks of :meth:`Explorer.checkpoint
<ramure.app.model.Explorer.checkpoint>` states.  Each entry also records how
many edits its session had applied when it was left (``position``): after
going back to it, Redo first re-applies that session's edits up to that
position, then moves forward to the next session.  Edits the user had undone
*before* leaving a session are not redone: the history stays one line, as in a
text editor.  A new edit clears the forward stack.

The number of sessions kept is bounded (:data:`MAX_STEPS`): each holds a
derivation, so a long typing spree does not grow memory without end; the
oldest are dropped first.

>>> class Ex:  # a stand-in for Explorer: a session with a list of edits
...     def __init__(self): self.state = ("a", 0)
...     def checkpoint(self): return self.state
...     def restore(self, cp): self.state = cp
>>> ex, t = Ex(), Timeline()
>>> t.leave(ex.checkpoint(), position=0); ex.state = ("b", 0)
>>> t.back(ex, position=0), ex.state
(True, ('a', 0))
>>> t.forward(ex, position=0), ex.state
(True, ('b', 0))
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.app.model import Explorer

MAX_STEPS = 30  # sessions kept behind (each holds a whole derivation)


class Timeline:
    """The sessions before and after the current one, for window-wide undo and redo."""

    def __init__(self, limit: int = MAX_STEPS) -> None:
        self.limit = int(limit)
        self.past: list = []  # (checkpoint, position when left), oldest first
        self.future: list = []  # (checkpoint, position to stop at), next first at the end

    @property
    def can_back(self) -> bool:
        return bool(self.past)

    @property
    def can_forward(self) -> bool:
        return bool(self.future)

    def leave(self, checkpoint: dict, position: int) -> None:
        """A session was replaced (new text, n or seed): remember its ``checkpoint``, left with
        ``position`` edits applied."""
        self.past.append((checkpoint, int(position)))
        del self.past[: -self.limit]
        self.future.clear()

    def new_edit(self) -> None:
        """A new edit on the current session: what was undone can no longer be redone."""
        self.future.clear()

    def back(self, explorer: Explorer, position: int) -> bool:
        """Return to the previous session (the current one is kept for Redo); False if none."""
        if not self.past:
            return False
        checkpoint, left_at = self.past.pop()
        self.future.append((explorer.checkpoint(), int(position), left_at))
        explorer.restore(checkpoint)
        return True

    def stop(self) -> int | None:
        """How many edits the current session had when it was left for the next one (None: last)."""
        return self.future[-1][2] if self.future else None

    def forward(self, explorer: Explorer, position: int) -> bool:
        """Go to the next session (the one Undo left); False if none."""
        if not self.future:
            return False
        checkpoint, _, _ = self.future.pop()
        self.past.append((explorer.checkpoint(), int(position)))
        explorer.restore(checkpoint)
        return True

    def clear(self) -> None:
        self.past.clear()
        self.future.clear()
