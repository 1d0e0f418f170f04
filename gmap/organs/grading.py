"""UNECE quality classes (Extra, Class I, Class II, out of grade) from measured defects.

The tables below are data: one :class:`Limit` per (species, defect measure), with the most a
fruit may show in each class and the clause of the standard it comes from.  :func:`grade_unece`
measures each defect from the facts of :func:`ramure.gmap.organs.defect_specs.apply_defects`
(millimetres, mm², fractions) and the fruit's shape (:func:`ramure.gmap.organs.malform.shape_facts`),
and returns the best class every limit allows, with each failed limit and by how much.

Standards (texts of the UNECE Working Party on Agricultural Quality Standards):

* tomatoes, **UNECE FFV-36** (2017 edition): minimum requirements II.A (intact, sound, fresh in
  appearance; the OECD explanatory brochure excludes "unhealed cracks (concentric or radial)" and
  "unhealed damage caused by hail, showing deep pitting"); Extra II.B.i ("free from defects,
  with the exception of very slight superficial defects"); Class I II.B.ii ("free of cracks",
  "slight skin defects", the brochure: "hail damage ... allowed" when slight); Class II II.B.iii
  ("healed cracks not more than 3 cm in length for round, ribbed or oblong tomatoes").
* apples, **UNECE FFV-50** (2017/2020): II.B.ii Class I "slight skin defects which must not
  extend over more than 2 cm in length for defects of elongated shape, 1 cm² of total surface
  area for other defects", "slight bruising not exceeding 1 cm² in total area, not
  discoloured"; II.B.iii Class II: 4 cm, 2.5 cm², bruising 1.5 cm² "which may be slightly
  discoloured".
* pears, **UNECE FFV-51** (2017/2020): II.B.ii Class I 2 cm / 1 cm²; II.B.iii Class II 4 cm /
  2.5 cm²; minimum requirements exclude "damage due to hail" that is severe and "serious bruising".

What was and was not found: the search tool returned the texts' structure and the tomato
brochure's wording (Class I free of cracks, slight hail damage allowed; unhealed cracks and deep
hail pits excluded), not the clause text with the numbers for apples and pears, nor any number
for "slight" hail damage or shrivel.  Every limit carries ``verified``: False where the number is
recalled from the standard, not checked against its text here, and ``chosen`` where the standard
gives no number and Ramure chose one conservatively (the tighter reading).

Bananas (**UNECE FFV-35**) and plums (**FFV-29**) or cherries (**FFV-13**) have standards of
their own; their classes are not tabulated here (:data:`NOT_TABULATED`): those fruit get the
OECD rule check only and ``grade_unece`` says so.

>>> g = grade_unece([{"kind": "crack", "length_mm": 25.0, "depth_layers": 1, "healed_layers": 1}], "tomato")
>>> g["grade"], g["reasons"][0].split(":")[0], [f["class"] for f in g["failed"]]
('Class II', 'Class I', ['Extra', 'Extra', 'Class I', 'Class I'])
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

from ramure.gmap.kernel.errors import ValueRefused

#: The classes, best first, then the verdict when even Class II fails.
CLASSES = ("Extra", "Class I", "Class II")
OUT = "out of grade"


@dataclass(frozen=True)
class Limit:
    """The most a fruit may show of one measure in each class (``None``: no limit in that class;
    ``math.inf`` never appears: a class without a limit says None)."""

    measure: str
    unit: str
    extra: float | None
    class_i: float | None
    class_ii: float | None
    clause: str
    verified: bool = True
    chosen: bool = False
    note: str = ""

    def bound(self, cls: str) -> float | None:
        """The limit of class ``cls``."""
        return {"Extra": self.extra, "Class I": self.class_i, "Class II": self.class_ii}[cls]


_ELONGATED = "II.B.ii/iii: skin defects of elongated shape 2 cm / 4 cm"
_OTHER = "II.B.ii/iii: other skin defects 1 cm2 / 2.5 cm2 total"

#: Measures every species shares: soundness and freshness (minimum requirements) and shape.
_COMMON = [
    Limit("rot_cells", "cells", 0, 0, 0, "II.A minimum requirements: sound, produce affected by rotting is excluded"),
    Limit("unhealed_wounds", "count", 0, 0, 0, "II.A minimum requirements: intact (fresh cracks, open hail wounds)"),
    Limit(
        "volume_lost_fraction",
        "fraction",
        0.01,
        0.03,
        0.05,
        "II.A minimum requirements: fresh in appearance (no withering)",
        chosen=True,
        note="the standard gives no number; 1 / 3 / 5 % volume lost chosen (shrivel shows from about 5 %)",
    ),
    Limit(
        "lopsidedness",
        "ratio",
        0.05,
        0.12,
        None,
        "II.B: Extra characteristic shape; Class I a slight defect in shape; Class II defects in shape",
        chosen=True,
        note="no number in the standard; centroid offset / mean radius of the widest ring",
    ),
    Limit("excrescence_mm", "mm", 0, 2.0, None, "II.B: shape and development", chosen=True, note="tallest excrescence"),
]

STANDARDS: dict[str, dict[str, Any]] = {
    "tomato": {
        "standard": "UNECE FFV-36 (2017)",
        "limits": [
            Limit("crack_count", "count", 0, 0, None, "II.B.i Extra free from defects; II.B.ii Class I: free of cracks"),
            Limit(
                "healed_crack_mm",
                "mm",
                0,
                0,
                30.0,
                "II.B.iii Class II: healed cracks not more than 3 cm in length (round, ribbed, oblong tomatoes)",
            ),
            Limit(
                "hail_area_mm2",
                "mm2",
                0,
                50.0,
                250.0,
                "II.B.ii Class I slight skin defects (brochure: hail damage allowed); II.B.iii Class II skin defects",
                chosen=True,
                note="'slight' has no number: 0.5 cm2 (Class I) and 2.5 cm2 (Class II, as apples) chosen",
            ),
            Limit(
                "hail_depth_mm",
                "mm",
                0,
                1.0,
                2.0,
                "II.A (brochure): unhealed hail damage showing deep pitting is excluded",
                chosen=True,
                note="'deep pitting' has no number: 1 mm (Class I) and 2 mm (Class II) chosen",
            ),
        ],
    },
    "apple": {
        "standard": "UNECE FFV-50 (2017)",
        "limits": [
            Limit("healed_crack_mm", "mm", 0, 20.0, 40.0, _ELONGATED, verified=False),
            Limit("hail_area_mm2", "mm2", 0, 100.0, 250.0, _OTHER, verified=False),
            Limit(
                "bruise_area_mm2",
                "mm2",
                0,
                100.0,
                150.0,
                "II.B.ii/iii: slight bruising 1 cm2 not discoloured / 1.5 cm2 slightly discoloured",
                verified=False,
            ),
        ],
    },
    "pear": {
        "standard": "UNECE FFV-51 (2017)",
        "limits": [
            Limit("healed_crack_mm", "mm", 0, 20.0, 40.0, _ELONGATED, verified=False),
            Limit("hail_area_mm2", "mm2", 0, 100.0, 250.0, _OTHER, verified=False),
            Limit(
                "bruise_area_mm2",
                "mm2",
                0,
                100.0,
                100.0,
                "II.A: serious bruising excluded; II.B.ii slight bruising",
                verified=False,
                chosen=True,
                note="bruise area for pears not found: the apple's Class I 1 cm2 used for both classes",
            ),
        ],
    },
}

#: Species with a UNECE standard whose classes Ramure does not tabulate (OECD rule check only).
NOT_TABULATED = {
    "banana": "UNECE FFV-35 (bananas) applies (Class I skin defects up to 2 cm2, Class II 4 cm2, "
    "for green bananas); not tabulated here: the OECD rule check only",
    "plum": "UNECE FFV-29 (plums) applies; not tabulated here: the OECD rule check only",
    "cherry": "UNECE FFV-13 (cherries) applies; not tabulated here: the OECD rule check only",
}


def limits(species: str) -> list[Limit]:
    """Every limit applied to ``species``: the shared minimum requirements and shape, then its table."""
    if species in NOT_TABULATED:
        return []
    if species not in STANDARDS:
        raise ValueRefused(f"no grading table for species {species!r}; known: {', '.join([*STANDARDS, *NOT_TABULATED])}")
    return [*_COMMON, *STANDARDS[species]["limits"]]


def measures(facts: Sequence[Mapping[str, Any]], fruit: Mapping[str, Any] | None = None) -> dict[str, float]:
    """The measured sizes the tables compare, from defect records (and the fruit's facts:
    ``volume_lost_fraction``, ``lopsidedness``)."""
    m = dict.fromkeys(
        (
            "rot_cells",
            "unhealed_wounds",
            "crack_count",
            "healed_crack_mm",
            "hail_area_mm2",
            "hail_depth_mm",
            "bruise_area_mm2",
            "excrescence_mm",
        ),
        0.0,
    )
    for f in facts:
        kind = f.get("kind")
        if kind == "crack":
            m["crack_count"] += 1
            healed = int(f.get("healed_layers", 0)) >= int(f.get("depth_layers", 1))
            if healed:
                m["healed_crack_mm"] = max(m["healed_crack_mm"], float(f.get("length_mm", 0.0)))
            else:
                m["unhealed_wounds"] += 1
        elif kind == "hail":
            craters = f.get("craters", [])
            area = sum(float(c.get("area_mm2", 0.0)) for c in craters)
            m["hail_area_mm2"] += area
            m["bruise_area_mm2"] += area
            m["hail_depth_mm"] = max([m["hail_depth_mm"], *(float(c.get("actual_depth_mm", 0.0)) for c in craters)])
            if not f.get("healed", 0):
                m["unhealed_wounds"] += len(craters)
        elif kind == "rot":
            m["rot_cells"] += float(sum(f.get("ring_cells", [1])))
        elif kind == "excrescence":
            m["excrescence_mm"] = max(m["excrescence_mm"], float(f.get("height_mm", 0.0)))
    fruit = fruit or {}
    m["volume_lost_fraction"] = max(0.0, float(fruit.get("volume_lost_fraction", 0.0)))
    m["lopsidedness"] = float(fruit.get("lopsidedness", 0.0))
    return m


def grade_unece(facts: Sequence[Mapping[str, Any]], species: str, fruit: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The UNECE class of a fruit from its defect records; see the module docstring.

    Returns ``grade`` (Extra, Class I, Class II, out of grade, or None when the species is not
    tabulated), ``standard``, ``measures`` and ``failed``: one record per limit a class failed
    (``class``, ``measure``, ``limit``, ``measured``, ``by`` = measured - limit, ``unit``,
    ``clause``, ``verified``, ``chosen``), and ``reasons``, one sentence per failure of the
    class just above the grade (or of Class II when out of grade).
    """
    if species in NOT_TABULATED:
        return {"grade": None, "standard": NOT_TABULATED[species], "measures": {}, "failed": [], "reasons": []}
    table = limits(species)
    measured = measures(facts, fruit)
    failed = []
    for cls in CLASSES:
        for lim in table:
            bound = lim.bound(cls)
            value = measured.get(lim.measure, 0.0)
            if bound is not None and value > bound + 1e-9:
                failed.append(
                    {
                        "class": cls,
                        "measure": lim.measure,
                        "limit": float(bound),
                        "measured": float(value),
                        "by": float(value - bound),
                        "unit": lim.unit,
                        "clause": lim.clause,
                        "verified": lim.verified,
                        "chosen": lim.chosen,
                    }
                )
    failing = {f["class"] for f in failed}
    grade = next((cls for cls in CLASSES if cls not in failing), OUT)
    blocker = "Class II" if grade == OUT else CLASSES[max(CLASSES.index(grade) - 1, 0)]
    reasons = [
        f"{f['class']}: {f['measure']} {f['measured']:.3g} {f['unit']} > {f['limit']:g} (by {f['by']:.3g}; {f['clause']})"
        for f in failed
        if f["class"] == blocker and grade != "Extra"
    ]
    return {
        "grade": grade,
        "standard": STANDARDS[species]["standard"],
        "measures": measured,
        "failed": failed,
        "reasons": reasons,
    }


def table_rows(species: str) -> list[dict[str, Any]]:
    """The species' limits as plain records (for docs, JSON and tests)."""
    return [asdict(lim) for lim in limits(species)]
