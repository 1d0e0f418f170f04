"""A parameter combination: the one spelling Ramure uses for "these constants, on this rule".

A combination is a plain dict, the form every layer reads and writes (the
variant sweep's :meth:`~ramure.metrics.sweep.VariantSweep.combination`,
qualifier results, session edits and files, study picks, the qualifier
store, the front ends' JSON)::

    {"rule": 1, "constants": {"r1": 0.9, "a2": 66.0}}    # only rule 1 reads these values
    {"rule": None, "constants": {"r1": 0.9}}             # every rule does

``rule`` is a rule index (0-based, in file order) or None; ``constants``
maps ``#define`` names to numbers.  :meth:`ramure.lsys.LSystem.derive`,
:func:`ramure.lsys.regeneration.regen.regenerate` and :meth:`ramure.lsys.regeneration.regen.Session.regrow`
take it as ``params=``; :func:`split` is the only place that turns it into
what the rewriting engine applies (global overrides, per-rule overrides).

>>> combination(1, {"r1": 0.9})
{'rule': 1, 'constants': {'r1': 0.9}}
>>> split({"rule": None, "constants": {"r1": 0.9}}), split({"rule": 2, "constants": {"k": 5}})
(({'r1': 0.9}, None), ({}, {2: {'k': 5.0}}))
>>> split(None)
({}, None)
"""

from __future__ import annotations

from ramure.errors import ValueRefused


def combination(rule: int | None, constants: dict) -> dict:
    """A parameter combination ``{"rule": rule, "constants": {name: float}}``."""
    return {"rule": None if rule is None else int(rule), "constants": {str(k): float(v) for k, v in dict(constants).items()}}


def split(params: dict | None) -> tuple[dict, dict | None]:
    """``(constants for every rule, {rule: constants} or None)`` of a combination (None: no change).

    A missing ``constants`` reads as none; anything else that is not a
    combination is refused in one line.
    """
    if params is None or params == {}:
        return {}, None
    if not isinstance(params, dict) or not isinstance(params.get("constants", {}), dict):
        raise ValueRefused(f"a parameter combination is {{'rule': index or None, 'constants': {{...}}}}, not {params!r}")
    rule = params.get("rule")
    try:
        values = {str(k): float(v) for k, v in params.get("constants", {}).items()}
        rule = None if rule is None else int(rule)
    except (TypeError, ValueError):
        raise ValueRefused(f"a combination's rule is an index and its constants numbers, not {params!r}") from None
    if rule is None:
        return values, None
    return {}, {rule: values}
