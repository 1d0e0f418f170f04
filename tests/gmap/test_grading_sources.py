"""Issue 40 §4: the UNECE grading tables against the words of the standards they cite.

A limit whose class is ``checked`` must carry the words it was read in, and its number must
be in them (in the text's unit: cm for mm, cm² for mm²), so the table cannot drift from its
citation; classes are ordered (Extra no looser than Class I, Class I no looser than Class II).
"""

import re

import pytest

from ramure.gmap.organs import grading as G
from ramure.gmap.organs.defect_specs import apply_defects
from ramure.gmap.organs.fruit import build_fruit

SPECIES = list(G.STANDARDS)
#: How a zero limit reads in a standard: the defect is excluded or must be absent.
ZERO_WORDS = ("excluded", "must not", "free of", "free from", "none allowed")
#: The unit a standard writes each table unit in, and the factor from the table's unit.
TEXT_UNIT = {"mm": ("cm", 0.1), "mm2": ("cm2", 0.01)}


def _all_limits():
    rows = [(s, None, lim) for s in SPECIES for lim in G.limits(s)]
    rows += [(s, p, lim) for s, types in G.TYPE_OVERRIDES.items() for p in types for lim in G.limits(s, p)]
    return rows


def _in_quote(value, unit, quote):
    """Is ``value`` (in the table's ``unit``) written in ``quote``?  "3cm", "3 cm", "2.5 cm²"."""
    if value == 0:
        return any(w in quote.lower() for w in ZERO_WORDS)
    if unit not in TEXT_UNIT:
        return False  # a count other than 0 is not written as a size
    text_unit, factor = TEXT_UNIT[unit]
    number = re.escape(f"{value * factor:g}").replace(r"\.", "[.,]")  # 2.5 or 2,5
    pattern = rf"(?<![\d.,]){number}\s?cm" + ("(2|²| 2)" if text_unit == "cm2" else r"(?![2²])")
    return re.search(pattern, quote) is not None


@pytest.mark.parametrize("species, preset, lim", _all_limits(), ids=lambda x: getattr(x, "measure", str(x)))
def test_each_checked_number_is_in_its_quote(species, preset, lim):
    assert set(lim.checked) <= set(G.CLASSES)
    if lim.checked:
        assert lim.quote and lim.source, f"{species} {lim.measure}: checked without the words or where they were read"
    for cls in lim.checked:
        bound = lim.bound(cls)
        if bound is not None:
            assert _in_quote(bound, lim.unit, lim.quote), f"{species} {lim.measure} {cls} {bound} not in {lim.quote!r}"
    if not lim.verified:
        assert lim.note, f"{species} {lim.measure}: an unchecked number must say why"
    assert not (lim.chosen and lim.checked), "a chosen number is not read in a text"


def test_quote_check_catches_a_drifted_number():
    quote = "Healed cracks not more than 3cm in length"
    assert _in_quote(30.0, "mm", quote) and not _in_quote(40.0, "mm", quote) and not _in_quote(3.0, "mm", quote)
    assert _in_quote(250.0, "mm2", "2.5 cm² of total surface area") and not _in_quote(25.0, "mm2", "2.5 cm²")
    assert _in_quote(150.0, "mm2", "nicht größer als 1,5 cm² sind") and not _in_quote(150.0, "mm2", "11,5 cm²")
    assert not _in_quote(20.0, "mm", "2 cm2 of total surface area")  # an area is no length
    assert _in_quote(0, "count", "None allowed") and not _in_quote(0, "count", "slight cracks")


@pytest.mark.parametrize("species, preset, lim", _all_limits(), ids=lambda x: getattr(x, "measure", str(x)))
def test_classes_are_ordered(species, preset, lim):
    loose = [float("inf") if lim.bound(c) is None else lim.bound(c) for c in G.CLASSES]
    assert loose == sorted(loose), f"{species} {lim.measure}: {loose}"


def test_checked_rows_are_the_ones_the_texts_gave():
    checked = {(s, lim.measure): lim.checked for s, p, lim in _all_limits() if p is None and lim.checked}
    assert checked == {
        **{(s, m): G.CLASSES for s in SPECIES for m in ("rot_cells", "unhealed_wounds")},
        ("tomato", "crack_count"): G.CLASSES,
        ("tomato", "healed_crack_mm"): G.CLASSES,
        **{("apple", m): ("Class I", "Class II") for m in ("healed_crack_mm", "hail_area_mm2", "bruise_area_mm2")},
        ("pear", "healed_crack_mm"): ("Class II",),
    }
    rows = {r["measure"]: r for r in G.table_rows("tomato")}
    assert rows["healed_crack_mm"]["verified"] and not rows["hail_area_mm2"]["verified"]


def test_pear_class_ii_bruise_is_the_other_defects_area():
    rows = {r["measure"]: r for r in G.table_rows("pear")}
    assert rows["bruise_area_mm2"]["class_ii"] == rows["hail_area_mm2"]["class_ii"] == 250.0
    assert rows["bruise_area_mm2"]["class_i"] == 100.0
    hail = {"kind": "hail", "healed": 1, "craters": [{"area_mm2": 90.0, "actual_depth_mm": 0.5}] * 2}
    g = G.grade_unece([hail], "pear")  # 1.8 cm² healed hail: over Class I's 1 cm², inside Class II's 2.5 cm²
    assert g["grade"] == "Class II"
    assert {f["measure"] for f in g["failed"] if f["class"] == "Class I"} == {"hail_area_mm2", "bruise_area_mm2"}


def test_failures_say_whether_their_number_was_checked():
    crack = {"kind": "crack", "length_mm": 45.0, "depth_layers": 1, "healed_layers": 1}
    pear = {(f["class"], f["measure"]): f["verified"] for f in G.grade_unece([crack], "pear")["failed"]}
    m = "healed_crack_mm"
    assert pear == {("Extra", m): False, ("Class I", m): False, ("Class II", m): True}
    apple = {(f["class"], f["measure"]): f["verified"] for f in G.grade_unece([crack], "apple")["failed"]}
    assert apple == {("Extra", m): False, ("Class I", m): True, ("Class II", m): True}


def test_cherry_tomato_has_no_class_ii_healed_crack():
    crack = {"kind": "crack", "length_mm": 12.0, "depth_layers": 1, "healed_layers": 1}
    assert G.grade_unece([crack], "tomato")["grade"] == "Class II"
    assert G.grade_unece([crack], "tomato", {"preset": "round_tomato"})["grade"] == "Class II"
    cherry = G.grade_unece([crack], "tomato", {"preset": "cherry_tomato"})
    assert cherry["grade"] == G.OUT and "oblong tomatoes" in cherry["reasons"][0]
    _, facts = apply_defects(build_fruit("cherry_tomato", volume_levels=1), ["crack:healed=1"])
    assert 0 < facts["defects"][0]["length_mm"] < 30.0  # within a round tomato's 3 cm ...
    fail = [f for f in facts["unece"]["failed"] if f["class"] == "Class II"]
    assert facts["unece"]["grade"] == G.OUT and [(f["measure"], f["limit"]) for f in fail] == [("healed_crack_mm", 0.0)]


def test_ribbed_tomato_class_i_allows_a_short_healed_crack():
    crack = {"kind": "crack", "length_mm": 8.0, "depth_layers": 1, "healed_layers": 1}
    assert G.grade_unece([crack], "tomato", {"preset": "round_tomato"})["grade"] == "Class II"
    ribbed = G.grade_unece([crack], "tomato", {"preset": "ribbed_tomato"})
    assert ribbed["grade"] == "Class I" and {f["class"] for f in ribbed["failed"]} == {"Extra"}
    longer = G.grade_unece([dict(crack, length_mm=12.0)], "tomato", {"preset": "ribbed_tomato"})
    assert longer["grade"] == "Class II" and "healed_crack_mm 12 mm > 10" in longer["reasons"][0]
    rows = {r["measure"]: r for r in G.table_rows("tomato", "ribbed_tomato")}
    assert rows["healed_crack_mm"]["class_i"] == 10.0 and rows["crack_count"]["class_i"] is None


def test_apple_hail_and_bruise_grade_at_the_quoted_areas():
    def hail(area):
        return {"kind": "hail", "healed": 1, "craters": [{"area_mm2": area, "actual_depth_mm": 0.5}]}

    assert G.grade_unece([hail(95.0)], "apple")["grade"] == "Class I"  # under 1 cm²
    assert G.grade_unece([hail(140.0)], "apple")["grade"] == "Class II"  # bruise 1.4 cm² <= 1.5
    g = G.grade_unece([hail(160.0)], "apple")  # over the 1.5 cm² bruise of Class II
    assert g["grade"] == G.OUT and [f["measure"] for f in g["failed"] if f["class"] == "Class II"] == ["bruise_area_mm2"]
