"""Global malformations of a volumetric fruit (Bohl 2015, ch. 3.1).

Two approaches, as in the thesis, both producing *fruit parameters* for
:func:`ramure.gmap.organs.fruit.build_fruit` (a malformed fruit is built malformed; nothing is
bent afterwards):

1. **Random parameters (Grammar 3.1)**: ``variation(x, taux) = x + U(-x taux, x taux)``
   and ``randomval(a, b) = U(a, b)`` on precision, ph, largeur, longueur, creux,
   nbprotus, anglesup, angleinf and nbvolangle (:data:`GRAMMAR_31`).  ``rate`` in
   [0, 1] says how far each parameter goes from the fruit's own value towards its
   Grammar 3.1 draw: ``value = own + rate (draw - own)``, so ``rate = 1`` is the
   thesis's grammar exactly and ``rate = 0`` the unchanged preset.  Whole-number
   parameters are rounded (the thesis does not say how); the printed
   ``nbvolangle = variation(5, precision)`` is a typo (spec, decision 8): it is
   ``variation(5, 50 %)``, capped at ``precision``.
2. **Bounding-surface constraints** (``variate`` per ring and ``hfunction`` per sector,
   see :mod:`ramure.gmap.organs.fruit`), chosen by name (:data:`SHAPES`): ``lopsided`` (the
   thesis's ``hfunction`` with ``fmin = 1``: one side twice the other), ``flattened``
   (short axis, ends pushed out by ``variate``: flat blossom and stem ends),
   ``ribbed`` (six deep ribs) and ``pointed`` (the thesis's Fig. 3.6 ``variate``:
   ``stepmax = 17/20`` of the rings, ``vmin_a = 0.2``, ``vmin_b = 0.8``).

:func:`shape_facts` measures what came out (flatness, lopsidedness, ribbing), so a label
says how malformed a fruit is, not only which recipe made it.

>>> p = malform_params("round_tomato", shape="lopsided")
>>> p["hamp"], p["fmin"]
(1.0, 1.0)
>>> q = malform_params("round_tomato", rate=1.0, seed=3)
>>> 5 <= q["precision"] <= 15 and 5 <= q["ph"] <= 17
True
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.organs.fruit import resolve_params

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3

#: Grammar 3.1: ``name -> ("variation", centre, taux)`` or ``("randomval", low, high)``.
GRAMMAR_31 = {
    "precision": ("variation", 10, 0.5),
    "ph": ("variation", 11, 0.5),
    "largeur": ("variation", 55.0, 0.2),
    "longueur": ("variation", 15.0, 0.1),
    "creux": ("variation", 0.5, 0.1),
    "nbprotus": ("randomval", 1, 8),
    "anglesup": ("randomval", 0.0, 20.0),
    "angleinf": ("randomval", -60.0, -30.0),
    "nbvolangle": ("variation", 5, 0.5),
}
#: Parameters rounded to whole numbers.
WHOLE = ("precision", "ph", "nbprotus", "nbvolangle", "stepmax")

#: Named bounding-surface constraints; values may depend on the fruit's own parameters.
SHAPES = {
    "lopsided": lambda p: {"fmin": 1.0, "hamp": 1.0},
    "flattened": lambda p: {
        "longueur": 0.6 * p["longueur"],
        "stepmax": p["precision"] // 2,
        "vmax": 1.0,
        "vmin_a": 1.35,
        "vmin_b": 1.35,
    },
    "ribbed": lambda p: {"ph": max(p["ph"], 24), "nbprotus": 6, "creux": 0.55},
    "pointed": lambda p: {
        "precision": max(p["precision"], 20),
        "stepmax": round(0.85 * max(p["precision"], 20)),
        "longueur": 1.2 * p["longueur"] * p["precision"] / max(p["precision"], 20),
        "vmax": 1.0,
        "vmin_a": 0.2,
        "vmin_b": 0.8,
    },
}


def _draw(name, rng):
    kind, a, b = GRAMMAR_31[name]
    if kind == "variation":
        return a + rng.uniform(-a * b, a * b)
    return rng.uniform(a, b)


def random_params(base: dict, rate: float, rng: np.random.Generator) -> dict:
    """Grammar 3.1 draws, ``rate`` of the way from ``base`` (resolved parameters); changed ones only."""
    out = {}
    for name in GRAMMAR_31:  # fixed order: the same seed gives the same fruit
        draw = _draw(name, rng)
        value = base[name] + rate * (draw - base[name])
        out[name] = int(round(value)) if name in WHOLE else float(value)
    out["precision"] = max(out["precision"], 3)
    out["ph"] = max(out["ph"], 3)
    out["nbprotus"] = max(out["nbprotus"], 0)
    out["nbvolangle"] = int(min(max(out["nbvolangle"], 0), out["precision"]))
    out["creux"] = float(min(max(out["creux"], 0.05), 1.0))
    return out


def malform_params(
    preset: str = "round_tomato", shape: str | None = None, rate: float = 0.0, seed: int = 0, **params: object
) -> dict[str, Any]:
    """Fruit parameters of a malformed ``preset``: ``params``, then Grammar 3.1 at ``rate``, then ``shape``.

    Returns the parameter overrides (pass them to ``build_fruit(preset, **out)``);
    they are checked here.  Refused: an unknown shape, a rate outside [0, 1].
    """
    if shape is not None and shape not in SHAPES:
        raise ValueRefused(f"unknown malformation {shape!r}; choose one of {', '.join(SHAPES)}")
    if not (isinstance(rate, (int, float)) and math.isfinite(rate) and 0 <= rate <= 1):
        raise ValueRefused(f"malformation rate must be in [0, 1], got {rate!r}")
    base = resolve_params(preset, **params)
    out: dict[str, Any] = dict(params)
    if rate > 0:
        out.update(random_params(base, float(rate), np.random.default_rng(seed)))
    if shape is not None:
        out.update(SHAPES[shape](resolve_params(preset, **out)))
    for name in WHOLE:
        if name in out:
            out[name] = int(round(float(out[name])))
    resolve_params(preset, **out)  # refuse now, naming the parameter
    return out


def parse_malform(spec: str) -> dict[str, Any]:
    """``"rate=0.2"``, ``"lopsided"``, ``"ribbed,rate=0.1"`` -> ``{"shape": ..., "rate": ...}``.

    >>> parse_malform("ribbed,rate=0.1")
    {'shape': 'ribbed', 'rate': 0.1}
    """
    out: dict[str, Any] = {"shape": None, "rate": 0.0}
    for item in filter(None, (x.strip() for x in str(spec).split(","))):
        name, sep, value = item.partition("=")
        name = name.strip().lower()
        if not sep:
            if name not in SHAPES:
                raise ValueRefused(f"--malform: unknown shape {name!r}; shapes: {', '.join(SHAPES)}, or rate=R (0..1)")
            out["shape"] = name
        elif name == "rate":
            try:
                out["rate"] = float(value)
            except ValueError:
                raise ValueRefused(f"--malform: rate={value!r} is not a number") from None
            if not (math.isfinite(out["rate"]) and 0 <= out["rate"] <= 1):
                raise ValueRefused(f"--malform: rate must be in [0, 1], got {value}")
        else:
            raise ValueRefused(f"--malform: expected a shape ({', '.join(SHAPES)}) or rate=R, got '{item}'")
    return out


def shape_facts(gm: GMap3) -> dict[str, float]:
    """How malformed the built fruit is, from its skin vertices around the axis (its local z).

    ``flatness`` = axis length / largest width (a round tomato ~0.8, flattened lower);
    ``lopsidedness`` = distance from the axis (the columella's mean) to the centroid of the skin's widest ring,
    over that ring's mean radius (0 when symmetric); ``ribbing`` = (max - min) / max of
    that ring's radius (0 for a smooth fruit).  Measured in the fruit's own frame, so
    call it before the fruit is placed in a plant.
    """
    vid, nv = gm.cells(0)
    free = gm.alpha[3] == np.arange(gm.n_darts)
    skin = np.unique(vid[free])
    first = np.full(nv, gm.n_darts, np.int64)
    np.minimum.at(first, vid, np.arange(gm.n_darts))
    pos = gm.points[first[skin]]
    axis_len = float(np.ptp(pos[:, 2]))
    width = float(max(np.ptp(pos[:, 0]), np.ptp(pos[:, 1])))
    trunk = gm.volume_data["order"][gm.dart_volume] == 0
    axis = gm.points[trunk, :2].mean(axis=0) if trunk.any() else pos[:, :2].mean(axis=0)
    pos = pos - np.r_[axis, 0.0]
    r = np.hypot(pos[:, 0], pos[:, 1])
    z_mid = pos[np.argmax(r), 2]
    band = np.abs(pos[:, 2] - z_mid) <= 0.08 * max(axis_len, 1e-12)
    ring = pos[band]
    rr = np.hypot(ring[:, 0], ring[:, 1])
    centre = ring[:, :2].mean(axis=0)
    return {
        "flatness": axis_len / width if width else 0.0,
        "lopsidedness": float(np.linalg.norm(centre) / max(rr.mean(), 1e-12)),
        "ribbing": float((rr.max() - rr.min()) / max(rr.max(), 1e-12)),
    }
