"""Fruit defects written as text (``kind:name=value,...``), for the CLI, the notebook and the desktop.

:func:`parse_defect` checks a spec; :func:`apply_defects` applies specs in order with the
functions of :mod:`ramure.gmap.organs.defects` and :mod:`ramure.gmap.organs.excrescence`
(kept apart from both so that neither imports the other's caller) and grades the result.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from typing import Any

from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.kernel.map3 import GMap3
from ramure.gmap.organs.defects import (
    ROT_COEFFICIENTS,
    crack,
    grade,
    hail,
    mm_per_unit,
    rot,
    shrink,
    skin_vertex_at,
    volumes_at,
    wrinkle,
)
from ramure.gmap.organs.excrescence import excrescence, parse_path
from ramure.gmap.organs.grading import grade_unece
from ramure.gmap.organs.malform import shape_facts

#: Defect kinds and the options each accepts (``kind:name=value,...``).
DEFECT_OPTIONS = {
    "shrink": ("rate", "steps", "kind", "wrinkle", "wave_mm"),
    "rot": ("vertex", "at", "coefficients", "rate", "steps"),
    "hail": ("count", "depth_mm", "stop", "vertex", "at", "healed"),
    "crack": ("kind", "sector", "rings", "depth", "width_mm", "healed"),
    "excrescence": ("path", "height_mm", "segments", "taper"),
}


def parse_defect(spec: str) -> tuple[str, dict[str, Any]]:
    """``"hail:count=5,depth_mm=2..6,stop=endocarp"`` -> ``("hail", {...})``, checked.

    Ranges are ``low..high``, ring spans ``3-6``; rot coefficients are ``2.5/2/1.5``.

    >>> parse_defect("hail:count=5,depth_mm=2..6")
    ('hail', {'count': 5, 'depth_mm': (2.0, 6.0)})
    """
    kind, _, rest = spec.partition(":")
    kind = kind.strip().lower()
    if kind not in DEFECT_OPTIONS:
        raise GMapError(f"unknown defect {kind!r} in '{spec}'; known: {', '.join(DEFECT_OPTIONS)}")
    opts = {}
    for item in filter(None, (x.strip() for x in _split_options(rest))):
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or name not in DEFECT_OPTIONS[kind]:
            raise GMapError(f"defect {kind}: expected NAME=VALUE with NAME in {', '.join(DEFECT_OPTIONS[kind])}, got '{item}'")
        opts[name] = _option_value(kind, name, value.strip())
    return kind, opts


def _split_options(text):
    """Split ``a=1,path=(3, C1, *),b=2`` on the commas outside parentheses."""
    items: list[str] = []
    cur: list[str] = []
    depth = 0
    for ch in text:
        depth += (ch == "(") - (ch == ")")
        if ch == "," and depth == 0:
            items.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    items.append("".join(cur))
    return items


def _option_value(kind, name, value):
    if name == "path":
        parse_path(value)  # a syntax error shows its caret now
        return value
    if name == "at":
        m = re.fullmatch(r"\s*ring\s*(\d+)\s*/\s*sector\s*(\d+)\s*", value)
        if not m:
            raise GMapError(f"defect {kind}: at={value!r} is not a place; write at=ringR/sectorS, e.g. at=ring4/sector2")
        return (int(m.group(1)), int(m.group(2)))
    try:
        if name == "rings":
            lo, sep, hi = value.partition("-")
            return (int(lo), int(hi if sep else lo))
        if name in ("steps", "count", "vertex", "sector", "depth", "healed", "segments"):
            number = float(value)
            if number != int(number):
                raise ValueError
            return int(number)
        if name == "depth_mm":
            lo, sep, hi = value.partition("..")
            return (float(lo), float(hi)) if sep else float(value)
        if name == "coefficients":
            return tuple(float(x) for x in value.split("/"))
        if name in ("stop", "kind"):
            return value
        return float(value)
    except ValueError:
        raise GMapError(f"defect {kind}: {name}={value!r} is not a valid value") from None


def apply_defects(
    gm: GMap3, specs: Iterable[str | tuple[str, Mapping[str, Any]]], size_mm: float | None = None, seed: int = 0
) -> tuple[GMap3, dict[str, Any]]:
    """Apply defect specs in order; returns the map and the facts.

    Facts: ``defects`` (one record per defect), ``volume_before``,
    ``volume_after``, ``volume_lost`` (fraction too, and in mm³), ``size_mm``, ``grade``
    (:func:`grade`, the OECD rule check) and ``unece`` (the UNECE class of the fruit's species,
    :func:`ramure.gmap.organs.grading.grade_unece`, with the change in lopsidedness the
    defects made as its shape measure).  Every spec is parsed before anything is
    applied; ``seed`` is offset per defect so two hail specs differ.
    Millimetres stay those of the fruit as given: after a shrink, a later
    defect is told the shrunk fruit's size in the same millimetres.
    """
    parsed = [parse_defect(s) if isinstance(s, str) else s for s in specs]
    scale = mm_per_unit(gm, size_mm)  # millimetres per unit of the fruit as given
    before = float(volumes_at(gm, gm.points).sum())
    out, records = gm, []
    for i, (kind, opts) in enumerate(parsed):
        size_i = scale / mm_per_unit(out, 1.0)  # the same millimetres after a shrink
        out, facts = _apply_one(out, kind, dict(opts), size_i, seed + 1000 * i)
        records.append(facts)
    after = float(volumes_at(gm, out.points).sum())  # dart ids are the input's
    # a crack's loss is its gap, not the flesh's bulge (of either sign) round it
    after -= sum(r.get("volume_lost", 0.0) + r.get("flesh_volume_change", 0.0) for r in records if r["kind"] == "crack")
    if out is gm:
        out = gm.copy()
    species = str(gm.meta.get("species", "tomato"))
    shape = {"lopsidedness": shape_facts(out)["lopsidedness"] - shape_facts(gm)["lopsidedness"]}  # what the defects changed
    out.meta["mm_per_unit"] = scale  # a shrunk fruit keeps the millimetres it was given
    return out, {
        "defects": records,
        "size_mm": scale * _extent(gm),
        "mm_per_unit": scale,
        "volume_before": before,
        "volume_after": after,
        "volume_lost": before - after,
        "volume_lost_fraction": (before - after) / before,
        "volume_before_mm3": before * scale**3,
        "volume_lost_mm3": (before - after) * scale**3,
        "grade": grade(records),
        "unece": grade_unece(
            records,
            species,
            {"volume_lost_fraction": (before - after) / before, "preset": gm.meta.get("preset"), **shape},
        ),
    }


def _shrivel(gm, opts, size_mm, seed):
    """Shrink, then wrinkle the skin: ``wrinkle`` (default 1) times half the radius the fruit lost
    (a 65 mm tomato shrunk 10 % per edge creases about 1.6 mm deep); ``wrinkle=0`` keeps it
    smooth (the thesis's homothety).  ``wave_mm``: the creases' wavelength in millimetres
    (default :data:`~ramure.gmap.organs.defects.WRINKLE_WAVELENGTH` of the fruit's size); keep
    it above twice the skin faces' width (about 2.5 mm on a twice subdivided 75 mm apple), or
    the skin only samples an alias of the pattern."""
    factor = opts.get("wrinkle", 1.0)
    if factor < 0:
        raise GMapError(f"shrink wrinkle must be >= 0 (0: smooth), got {factor}")
    wave = opts.get("wave_mm")
    if wave is not None and not (math.isfinite(wave) and wave > 0):
        raise GMapError(f"shrink wave_mm must be > 0 mm, got {wave}")
    out, facts = shrink(gm, opts.get("rate", 0.1), opts.get("steps", 1), rate_kind=opts.get("kind", "edge"))
    linear = 1.0 - facts["volume_kept"] ** (1.0 / 3.0)
    amplitude = factor * 0.5 * (0.5 * size_mm) * linear
    if amplitude > 0:
        out, w = wrinkle(out, amplitude, wave, size_mm=size_mm * (1.0 - linear), seed=seed)
        facts["wrinkle_wavelength_mm"] = w["wavelength_mm"]
        after = float(volumes_at(out, out.points).sum())
        facts.update(wrinkle_mm=w["amplitude_mm"], volume_after=after, volume_lost=facts["volume_before"] - after)
        facts["volume_kept"] = after / facts["volume_before"]
    return out, facts


def _extent(gm):
    """Largest bounding-box extent of the fruit, model units."""
    _, pos = gm.vertex_positions()
    return float((pos.max(axis=0) - pos.min(axis=0)).max())


def _apply_one(gm, kind, opts, size_mm, seed):
    if kind == "shrink":
        return _shrivel(gm, opts, size_mm, seed)
    if kind == "rot":
        vertex = opts.get("vertex")
        if "at" in opts:
            vertex = skin_vertex_at(gm, *opts["at"])
        out, facts = rot(gm, vertex, opts.get("coefficients", ROT_COEFFICIENTS), seed=seed)
        if opts.get("rate", 0.0) > 0:
            out, dried = shrink(out, opts["rate"], opts.get("steps", 1))
            facts.update(rate=dried["rate"], steps=dried["steps"], volume_lost=dried["volume_lost"])
        return out, facts
    if kind == "crack":
        return crack(
            gm,
            opts.get("kind", "longitudinal"),
            opts.get("sector", 0),
            opts.get("rings"),
            opts.get("depth", 1),
            opts.get("width_mm", 1.0),
            opts.get("healed", 0),
            size_mm,
        )
    if kind == "excrescence":
        if "path" not in opts:
            raise GMapError("excrescence: give a path, e.g. excrescence:path=(9, C*, *)")
        return excrescence(gm, opts["path"], opts.get("height_mm", 3.0), opts.get("segments", 1), opts.get("taper", 0.5), size_mm)
    vertices = None if "vertex" not in opts else [opts["vertex"]]
    if "at" in opts:  # the middle of a branch's skin, named by labels (survives subdivision)
        vertices = [skin_vertex_at(gm, *opts["at"])]
    return hail(
        gm, vertices, opts.get("depth_mm", (2.0, 6.0)), opts.get("count"), opts.get("stop"), size_mm, seed, opts.get("healed", 0)
    )
