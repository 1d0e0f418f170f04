"""UNECE quality classes (Extra, Class I, Class II, out of grade) from measured defects.

The tables below are data: one :class:`Limit` per (species, defect measure), with the most a
fruit may show in each class, the clause of the standard it comes from, and, for the classes
whose number was read in a text (``checked``), the words read (``quote``) and where
(``source``).  :func:`grade_unece` measures each defect from the facts of
:func:`ramure.gmap.organs.defect_specs.apply_defects` (millimetres, mm², fractions) and the
fruit's shape (:func:`ramure.gmap.organs.malform.shape_facts`), and returns the best class every
limit allows, with each failed limit, by how much, and whether that number was checked.

Standards: tomatoes **UNECE FFV-36** (2017), apples **FFV-50** (2017/2020), pears **FFV-51**
(2017/2020), texts of the UNECE Working Party on Agricultural Quality Standards, copied word
for word by the EU marketing standards (Reg. (EU) 543/2011 Annex I Part B, then 2019/428 and
2023/2429) and explained by the OECD brochures.  Those copies count as sources.

Where each checked number was read (the ``source`` of its row):

* minimum requirements, all three species: "intact", "sound; produce affected by rotting or
  deterioration such as to make it unfit for consumption is excluded" -- the apple standard of
  Reg. (EU) 543/2011 Annex I Part B Part 1 (consolidated text, vdocuments.net "Commission
  Implementing Regulation (EU) No 543/2011 ... Part 1 of Part B Marketing standard for apples"),
  the pear standard of Reg. (EU) 2019/428 Annex Part 6 as retained in the UK
  (legislation.gov.uk/eur/2019/428/annex/part/6), and the OECD tomato brochure's text on
  leafconagro.com/minimum-requirements-of-tomatoes, which also reads "the tomatoes must not
  have any damage or injury affecting the integrity of the produce" and excludes "unhealed
  cracks (concentric or radial) caused by growth phenomena" and "unhealed damage caused by
  hail, showing deep pitting or corky roughness";
* tomatoes, cracks: Extra "free from greenbacks and other defects", Class I "They must be free
  of cracks and visible greenbacks" (OECD brochure text, leafconagro.com/classification-of-tomatoes);
  "Healed Cracks Class I – None allowed Class II - Healed cracks not more than 3cm in length for
  round, ribbed or oblong tomatoes" (Ian Hewett, Horticultural Marketing Inspectorate (UK),
  "Tomatoes" training slides on the UNECE standard, Ghana 2011, paperzz.com/doc/6905452); the
  German federal inspection (BLE, FAQ TOM_05 on Reg. 543/2011 Annex I Part B Part 10): "Tomaten
  der Klasse II können mehrere vernarbte Risse von höchstens 3 cm Länge aufweisen" (several
  healed cracks, each up to 3 cm: the table compares the longest);
* ribbed tomatoes, Class I: "bei gerippten Tomaten vernarbte Risse (Länge maximal 1 cm)"
  (aid infodienst, "Tomaten: Einkauf und Kennzeichnung", aid.de/inhalt/einkauf-und-kennzeichnung-6299);
* apples, skin defects and bruises (Reg. 543/2011 Annex I Part B Part 1, the words of FFV-50
  II.B.ii/iii as German inspectors state them): Class I "leichte längliche Schalenfehler bis zu
  2 cm Länge, sonstige Schalenfehler bis zu einer Gesamtfläche von 1 cm2 pro Frucht", Class II
  "längliche Schalenfehler bis zu 4 cm Länge, sonstige Schalenfehler bis zu einer Gesamtfläche
  von 2,5 cm2 pro Frucht", and hail damage is graded as these defects ("Hagelschäden können
  unter die Kategorie folgender zulässiger Fehler fallen") -- Landwirtschaftskammer
  Niedersachsen, "Hagelschaden bei Apfel – wie ist die Qualität zu beurteilen?"
  (lwk-niedersachsen.de/lwk/news/34964); bruises: "nicht mehr als 1 cm² ... Klasse I ...,
  sofern das Fruchtfleisch nicht verfärbt ist", "nicht größer als 1,5 cm² ... nur leichte,
  unverkorkte Verfärbungen ... Klasse II" (BLE, FAQ APF_07 "Wie tief müssen Äpfel geschält
  werden ...", on Reg. 543/2011 Annex I Part B Part 1);
* pears, Class II elongated skin defects: "Skin defects which must not extend over more than
  4 cm in length for defects of elongated shape" and "Of total surface area for other defects
  including slightly discoloured bruising" -- the AGMARK (India) pear grade, which reproduces
  the UNECE Class II wording (its scab clause names Venturia), as transcribed in a public
  repository's data file (exact-string search of the code index; the index does not name the
  repository).  That second sentence puts a pear's slightly discoloured bruise inside the
  Class II area for other defects, so the pear bruise limit of Class II is that area
  (2.5 cm²), not the Class I 1 cm² the table had (fixed here; the 2.5 itself is not checked).

What was searched and not found (every class missing from a row's ``checked``): the pear
Class I numbers (2 cm, 1 cm², bruising 1 cm²) and Class II area (2.5 cm²), and any Extra
number for apples and pears (the text allows "very slight superficial defects" with no
number; 0 is the table's reading).  The stored pages of docslib.org, readkong.com,
docplayer.net/.org, legislation.gov.uk, vdocuments.net, vog.de and the OECD pear brochure
copies hold FFV-51 or its EU copy, but only their first pages (notes, definition, minimum
requirements) are searchable; queries on the class wording (English "slight skin defects
which must not extend over more than", "slight bruising not exceeding", "Venturia ... 0.25
cm²"; German "Druckstellen", "Schalenfehler"; French "meurtrissures") over the pages, docs,
code and issues corpora, and exact-string searches of the code index, found no pear text with
those numbers.  Nothing gives a number for "slight" hail damage on tomatoes, "deep pitting"
or shrivel: those rows are ``chosen`` (Ramure picked the tighter reading) and say so in their
``note``.

Commercial type (:data:`TYPE_OVERRIDES`, chosen by ``fruit["preset"]``): FFV-36 allows Class
II healed cracks "for round, ribbed or oblong tomatoes", so a cherry tomato gets none in any
class (the reading of that "for"); a ribbed tomato may show healed cracks up to 1 cm in
Class I.

Bananas (**UNECE FFV-35**) and plums (**FFV-29**) or cherries (**FFV-13**) have standards of
their own; their classes are not tabulated here (:data:`NOT_TABULATED`): those fruit get the
OECD rule check only and ``grade_unece`` says so.

>>> g = grade_unece([{"kind": "crack", "length_mm": 25.0, "depth_layers": 1, "healed_layers": 1}], "tomato")
>>> g["grade"], g["reasons"][0].split(":")[0], [f["class"] for f in g["failed"]]
('Class II', 'Class I', ['Extra', 'Extra', 'Class I', 'Class I'])
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any

from ramure.gmap.kernel.errors import ValueRefused

#: The classes, best first, then the verdict when even Class II fails.
CLASSES = ("Extra", "Class I", "Class II")
OUT = "out of grade"
ALL = CLASSES


@dataclass(frozen=True)
class Limit:
    """The most a fruit may show of one measure in each class (``None``: no limit in that class;
    ``math.inf`` never appears: a class without a limit says None).

    ``checked`` names the classes whose bound was read in ``quote`` (the standard's words, or
    a copy's, exactly as read) at ``source``; ``chosen`` says Ramure picked the number where
    the text gives none; ``note`` says what is missing or how the number was read.
    """

    measure: str
    unit: str
    extra: float | None
    class_i: float | None
    class_ii: float | None
    clause: str
    checked: tuple[str, ...] = ()
    chosen: bool = False
    quote: str = ""
    source: str = ""
    note: str = ""

    def bound(self, cls: str) -> float | None:
        """The limit of class ``cls``."""
        return {"Extra": self.extra, "Class I": self.class_i, "Class II": self.class_ii}[cls]

    @property
    def verified(self) -> bool:
        """True when every class's bound was read in the quoted text."""
        return set(CLASSES) <= set(self.checked)


_MIN_REQ = (
    "Reg. (EU) 543/2011 Annex I Part B Part 1 (apples, consolidated, vdocuments.net); Reg. (EU) 2019/428 Annex Part 6 "
    "(pears, legislation.gov.uk/eur/2019/428/annex/part/6); OECD tomato brochure text "
    "(leafconagro.com/minimum-requirements-of-tomatoes)"
)
_OECD_TOMATO = "OECD tomato brochure text for FFV-36 (leafconagro.com/classification-of-tomatoes)"
_HEWETT = (
    "I. Hewett, Horticultural Marketing Inspectorate (UK), 'Tomatoes' training slides on the UNECE standard, "
    "Ghana 2011 (paperzz.com/doc/6905452/tomatoes-ghana-2011)"
)
_AGMARK_PEAR = (
    "AGMARK (India) pear grade, Class II, reproducing the UNECE FFV-51 wording; transcribed in a public repository "
    "data file (code index, exact-string search)"
)
_BLE_TOMATO = "BLE (German federal inspection), FAQ TOM_05 on Reg. (EU) 543/2011 Annex I Part B Part 10"
_AID_TOMATO = "aid infodienst, 'Tomaten: Einkauf und Kennzeichnung' (aid.de/inhalt/einkauf-und-kennzeichnung-6299)"
_LWK_APPLE = (
    "Landwirtschaftskammer Niedersachsen, 'Hagelschaden bei Apfel – wie ist die Qualität zu beurteilen?' "
    "(lwk-niedersachsen.de/lwk/news/34964), on the EU apple standard (Reg. (EU) 543/2011 Annex I Part B Part 1)"
)
_BLE_APPLE = "BLE (German federal inspection), FAQ APF_07 on Reg. (EU) 543/2011 Annex I Part B Part 1"
_NOT_FOUND = "clause text with this number not found (see the module docstring); recalled from the standard"
_EXTRA_NONE = "Extra: the text allows 'very slight superficial defects' with no number; 0 is the table's reading"

#: Measures every species shares: soundness and freshness (minimum requirements) and shape.
_COMMON = [
    Limit(
        "rot_cells",
        "cells",
        0,
        0,
        0,
        "II.A minimum requirements: sound, produce affected by rotting is excluded",
        checked=ALL,
        quote="sound; produce affected by rotting or deterioration such as to make it unfit for consumption is excluded",
        source=_MIN_REQ,
    ),
    Limit(
        "unhealed_wounds",
        "count",
        0,
        0,
        0,
        "II.A minimum requirements: intact (fresh cracks, open hail wounds)",
        checked=ALL,
        quote="intact … must not have any damage or injury affecting the integrity of the produce",
        source=_MIN_REQ,
    ),
    Limit(
        "volume_lost_fraction",
        "fraction",
        0.01,
        0.03,
        0.05,
        "tomatoes II.A: fresh in appearance; apples, pears II: after dispatch 'a slight lack of freshness and turgidity'",
        chosen=True,
        quote="TOMATOES MUST NOT SHOW ANY SIGN OF WITHERING OR LOSS OF FIRMNESS",
        source=_MIN_REQ,
        note="the standards give no number; 1 / 3 / 5 % volume lost chosen (shrivel shows from about 5 %)",
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

_ELONGATED = "II.B.ii/iii: skin defects of elongated shape 2 cm / 4 cm"
_OTHER = "II.B.ii/iii: other skin defects 1 cm2 / 2.5 cm2 total"

STANDARDS: dict[str, dict[str, Any]] = {
    "tomato": {
        "standard": "UNECE FFV-36 (2017)",
        "limits": [
            Limit(
                "crack_count",
                "count",
                0,
                0,
                None,
                "II.B.i Extra free from defects; II.B.ii Class I: free of cracks; II.B.iii Class II healed cracks",
                checked=ALL,
                quote="Extra: They must be free from greenbacks and other defects … Class I: They must be free of cracks "
                "and visible greenbacks. … Class II - Healed cracks not more than 3cm in length",
                source=f"{_OECD_TOMATO}; {_HEWETT}",
                note="Class II has no count limit: its healed cracks are limited by length (healed_crack_mm)",
            ),
            Limit(
                "healed_crack_mm",
                "mm",
                0,
                0,
                30.0,
                "II.B.iii Class II: healed cracks not more than 3 cm in length (round, ribbed, oblong tomatoes)",
                checked=ALL,
                quote="Healed Cracks Class I – None allowed Class II - Healed cracks not more than 3cm in length for "
                "round, ribbed or oblong tomatoes … Tomaten der Klasse II können mehrere vernarbte Risse von höchstens "
                "3 cm Länge aufweisen",
                source=f"{_HEWETT}; {_BLE_TOMATO}",
                note="several healed cracks may each reach 3 cm (BLE): the measure is the longest",
            ),
            Limit(
                "hail_area_mm2",
                "mm2",
                0,
                50.0,
                250.0,
                "II.B.ii Class I slight skin defects (brochure: hail damage allowed); II.B.iii Class II skin defects",
                chosen=True,
                quote="Slight skin defects such as scorching due to sun or chemical treatment, hail damage or slight "
                "damage caused by pests or disease are allowed",
                source=_OECD_TOMATO,
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
                quote="UNHEALED DAMAGE CAUSED BY HAIL, SHOWING DEEP PITTING OR CORKY ROUGHNESS",
                source=_MIN_REQ,
                note="'deep pitting' has no number: 1 mm (Class I) and 2 mm (Class II) chosen",
            ),
        ],
    },
    "apple": {
        "standard": "UNECE FFV-50 (2017)",
        "limits": [
            Limit(
                "healed_crack_mm",
                "mm",
                0,
                20.0,
                40.0,
                _ELONGATED,
                checked=("Class I", "Class II"),
                quote="Klasse I … leichte längliche Schalenfehler bis zu 2 cm Länge … Klasse II … längliche "
                "Schalenfehler bis zu 4 cm Länge",
                source=_LWK_APPLE,
                note=_EXTRA_NONE,
            ),
            Limit(
                "hail_area_mm2",
                "mm2",
                0,
                100.0,
                250.0,
                _OTHER,
                checked=("Class I", "Class II"),
                quote="Hagelschäden können unter die Kategorie folgender zulässiger Fehler fallen … Klasse I … sonstige "
                "Schalenfehler bis zu einer Gesamtfläche von 1 cm2 pro Frucht … Klasse II … sonstige Schalenfehler bis "
                "zu einer Gesamtfläche von 2,5 cm2 pro Frucht",
                source=_LWK_APPLE,
                note=_EXTRA_NONE,
            ),
            Limit(
                "bruise_area_mm2",
                "mm2",
                0,
                100.0,
                150.0,
                "II.B.ii/iii: slight bruising 1 cm2 not discoloured / 1.5 cm2 slightly discoloured",
                checked=("Class I", "Class II"),
                quote="Bedecken die sichtbaren Druckstellen auf einem Apfel insgesamt nicht mehr als 1 cm², könnte der "
                "Apfel der Klasse I entsprechen, sofern das Fruchtfleisch nicht verfärbt ist. … Bei Früchten, die "
                "äußerlich sichtbare Druckstellen aufweisen, die zusammengenommen nicht größer als 1,5 cm² sind, … "
                "Zeigt die geschälte Frucht nur leichte, unverkorkte Verfärbungen, handelt es sich um eine Frucht der "
                "Klasse II.",
                source=_BLE_APPLE,
                note=_EXTRA_NONE,
            ),
        ],
    },
    "pear": {
        "standard": "UNECE FFV-51 (2017)",
        "limits": [
            Limit(
                "healed_crack_mm",
                "mm",
                0,
                20.0,
                40.0,
                _ELONGATED,
                checked=("Class II",),
                quote="Skin defects which must not extend over more than 4 cm in length for defects of elongated shape",
                source=_AGMARK_PEAR,
                note="Class I 2 cm: " + _NOT_FOUND,
            ),
            Limit("hail_area_mm2", "mm2", 0, 100.0, 250.0, _OTHER, note=_NOT_FOUND),
            Limit(
                "bruise_area_mm2",
                "mm2",
                0,
                100.0,
                250.0,
                "II.A: serious bruising excluded; II.B.ii slight bruising 1 cm2; II.B.iii slightly discoloured bruising "
                "counts in the 2.5 cm2 of other defects",
                quote="Of total surface area for other defects including slightly discoloured bruising",
                source=_AGMARK_PEAR,
                note="Class II: the quote puts bruising inside the other-defects area, so its bound is hail_area_mm2's "
                "(whose 2.5 cm2 is not checked); Class I 1 cm2: " + _NOT_FOUND,
            ),
        ],
    },
}

#: Rows that change with the commercial type (preset), by species, preset and measure.
TYPE_OVERRIDES: dict[str, dict[str, dict[str, dict[str, Any]]]] = {
    "tomato": {
        "cherry_tomato": {
            "healed_crack_mm": {
                "class_ii": 0,
                "checked": ("Extra", "Class I"),
                "note": "FFV-36 allows Class II healed cracks 'for round, ribbed or oblong tomatoes': none for cherry "
                "tomatoes (the reading of that 'for')",
            }
        },
        "ribbed_tomato": {
            "crack_count": {
                "class_i": None,
                "checked": ("Extra",),
                "note": "ribbed tomatoes may show healed cracks in Class I, limited by length (healed_crack_mm)",
            },
            "healed_crack_mm": {
                "class_i": 10.0,
                "checked": ("Class I", "Class II"),
                "quote": "Außerdem sind bei gerippten Tomaten vernarbte Risse (Länge maximal 1 cm) … zulässig. … Tomaten "
                "der Klasse II können mehrere vernarbte Risse von höchstens 3 cm Länge aufweisen",
                "source": f"{_AID_TOMATO}; {_BLE_TOMATO}",
                "note": "Extra 0: ribbed tomatoes' Class I allowance does not reach Extra (the table's reading)",
            },
        },
    }
}

#: Species with a UNECE standard whose classes Ramure does not tabulate (OECD rule check only).
NOT_TABULATED = {
    "banana": "UNECE FFV-35 (bananas) applies (Class I skin defects up to 2 cm2, Class II 4 cm2, "
    "for green bananas); not tabulated here: the OECD rule check only",
    "plum": "UNECE FFV-29 (plums) applies; not tabulated here: the OECD rule check only",
    "cherry": "UNECE FFV-13 (cherries) applies; not tabulated here: the OECD rule check only",
}


def limits(species: str, preset: str | None = None) -> list[Limit]:
    """Every limit applied to ``species``: the shared minimum requirements and shape, then its
    table, with the rows its commercial type ``preset`` changes (:data:`TYPE_OVERRIDES`)."""
    if species in NOT_TABULATED:
        return []
    if species not in STANDARDS:
        raise ValueRefused(f"no grading table for species {species!r}; known: {', '.join([*STANDARDS, *NOT_TABULATED])}")
    changes = TYPE_OVERRIDES.get(species, {}).get(preset or "", {})
    return [replace(lim, **changes.get(lim.measure, {})) for lim in [*_COMMON, *STANDARDS[species]["limits"]]]


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
    ``clause``, ``verified``: that class's number was read in a text, ``chosen``), and
    ``reasons``, one sentence per failure of the class just above the grade (or of Class II
    when out of grade).  ``fruit`` may carry ``preset`` (the commercial type, e.g.
    ``cherry_tomato``) besides the measures :func:`measures` reads.
    """
    if species in NOT_TABULATED:
        return {"grade": None, "standard": NOT_TABULATED[species], "measures": {}, "failed": [], "reasons": []}
    table = limits(species, (fruit or {}).get("preset"))
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
                        "verified": cls in lim.checked,
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


def table_rows(species: str, preset: str | None = None) -> list[dict[str, Any]]:
    """The species' limits as plain records (for docs, JSON and tests), with ``verified``."""
    return [{**asdict(lim), "verified": lim.verified} for lim in limits(species, preset)]
