"""One undo history for the explorer: grammar text, constants, n, seed and plant edits.

:class:`~ramure.app.model.Explorer` keeps one :class:`Timeline` (both front ends undo
through it).

The model's :class:`~ramure.lsys.regeneration.regen.Session` keeps the plant edits
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


def history_words(verb: str, edit: dict | None, old: dict | None = None, new: dict | None = None) -> str:
    """What an Undo or Redo did, in the user's words: ``verb`` ("Undid", "Redid") and the step.

    ``edit``: the session edit it took back or brought again (``{"op": "document"}`` for a text,
    ``n`` or seed change, described from ``old`` and ``new``: the document states, dicts of
    text, n, seed and constants, before and after that change).

    >>> history_words("Undid", {"op": "regrow", "selection": [4, 7, 9], "constants": {}, "params": None})
    'Undid: regrow of 3 leaves'
    >>> history_words("Redid", {"op": "constants", "values": {"a2": 45.0}})
    'Redid: a2 = 45'
    >>> history_words("Undid", {"op": "document"}, {"text": "t", "n": 10, "seed": 0, "constants": {}},
    ...               {"text": "t", "n": 12, "seed": 0, "constants": {}})
    'Undid: n = 12'
    >>> history_words("Redid", None)
    'Nothing to redo'
    """
    if edit is None:
        return f"Nothing to {'undo' if verb == 'Undid' else 'redo'}"
    return f"{verb}: {_step_words(edit, old or {}, new or {})}"


def _count(items, one: str, many: str) -> str:
    return f"{len(items)} {one if len(items) == 1 else many}"


def _values(values: dict) -> str:
    return ", ".join(f"{name} = {float(value):g}" for name, value in values.items())


def _step_words(edit: dict, old: dict, new: dict) -> str:
    op = edit.get("op")
    if op == "regrow":
        where = _count(edit["selection"], "leaf", "leaves") if edit.get("selection") else "the whole plant"
        constants = {**((edit.get("params") or {}).get("constants") or {}), **(edit.get("constants") or {})}
        return f"regrow of {where}" + (f" with {_values(constants)}" if constants else "")
    if op == "prune":
        return f"prune of {_count(edit['selection'], 'leaf', 'leaves')}"
    if op == "constants":
        return _values(edit["values"])
    if op == "fruit":
        return f"new fruit for {_count(edit['leaves'], 'fruit', 'fruit')}"
    if op == "detail":
        leaves = edit.get("leaves") or []
        return f"{edit.get('kind', 'detail')}" + (f" on {_count(leaves, 'leaf', 'leaves')}" if leaves else "")
    return _document_words(old, new)


def _document_words(old: dict, new: dict) -> str:
    """A change of the document: its ``n``, seed, constants, or else its text."""
    parts = [f"{key} = {new[key]}" for key in ("n", "seed") if key in new and old.get(key) != new[key]]
    constants = new.get("constants") or {}
    changed = {k: v for k, v in constants.items() if (old.get("constants") or {}).get(k) != v}
    if changed and old.get("text") == new.get("text"):
        parts.append(_values(changed))
    if not parts:
        return "a change of the grammar text" if old.get("text") != new.get("text") else "a change of the plant"
    return ", ".join(parts)
