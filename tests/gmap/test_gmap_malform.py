"""Malformations (issue 17): Grammar 3.1 random parameters and bounding-surface constraints."""

import json

import numpy as np
import pytest

from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.organs.fruit import build_fruit, hfunction, resolve_params, variate
from ramure.gmap.organs.malform import GRAMMAR_31, SHAPES, malform_params, parse_malform, shape_facts


def branch_lengths(gm):
    """(ring, sector) -> branch H of an unsubdivided fruit."""
    vd = gm.volume_data
    b = np.flatnonzero(vd["order"] == 1)
    out = np.zeros((vd["ring"][b].max() + 1, vd["sector"][b].max() + 1))
    out[vd["ring"][b], vd["sector"][b]] = vd["size"][b, 0]
    return out


def test_constraints_multiply_branch_lengths_exactly():
    plain = branch_lengths(build_fruit("round_tomato"))
    lop = branch_lengths(build_fruit("round_tomato", hamp=1.0, fmin=1.0))
    np.testing.assert_allclose(lop / plain, np.broadcast_to(hfunction(10, 1.0, 1.0), plain.shape), rtol=1e-12)
    assert hfunction(10, 1.0, 1.0)[0] == 1.0 and hfunction(9, 1.0, 1.0)[4] == pytest.approx(2.0)
    ver = branch_lengths(build_fruit("round_tomato", stepmax=6, vmax=1.0, vmin_a=0.2, vmin_b=0.8))
    v = variate(10, 6, 1.0, 0.2, 0.8)
    np.testing.assert_allclose(ver / plain, np.broadcast_to(v[:, None], plain.shape), rtol=1e-12)
    assert v[0] == pytest.approx(0.2) and v[6] == pytest.approx(1.0) and v[9] == pytest.approx(1 - 0.2 * 3 / 4)


def test_rate_zero_is_the_preset_and_rate_one_the_thesis_ranges():
    assert malform_params("round_tomato", rate=0.0, seed=5) == {}
    seen = {name: [] for name in GRAMMAR_31}
    for seed in range(40):
        p = malform_params("round_tomato", rate=1.0, seed=seed)
        for name in GRAMMAR_31:
            seen[name].append(p[name])
    lo_hi = {
        "precision": (5, 15),
        "ph": (5, 17),
        "largeur": (44, 66),
        "longueur": (13.5, 16.5),
        "creux": (0.45, 0.55),
        "nbprotus": (1, 8),
        "anglesup": (0, 20),
        "angleinf": (-60, -30),
    }
    for name, (lo, hi) in lo_hi.items():
        assert lo <= min(seen[name]) and max(seen[name]) <= hi, name
        assert len(set(seen[name])) > 3, name  # it does vary
    assert all(isinstance(x, int) for x in seen["precision"] + seen["ph"] + seen["nbprotus"])
    # a small rate stays near the preset
    base = resolve_params("round_tomato")
    small = malform_params("round_tomato", rate=0.1, seed=1)
    assert abs(small["largeur"] - base["largeur"]) <= 0.1 * abs(55 * 1.2 - base["largeur"]) + 1e-9


def test_deterministic_per_seed():
    a = malform_params("round_tomato", rate=0.5, seed=7)
    assert a == malform_params("round_tomato", rate=0.5, seed=7)
    assert a != malform_params("round_tomato", rate=0.5, seed=8)


def test_named_shapes_measure_as_named():
    facts = {
        name: shape_facts(build_fruit("round_tomato", volume_levels=1, **malform_params("round_tomato", shape=name)))
        for name in (None, *SHAPES)
    }
    plain = facts[None]
    assert plain["lopsidedness"] < 1e-6 and plain["ribbing"] < 0.03
    assert facts["lopsided"]["lopsidedness"] > 0.05
    assert facts["flattened"]["flatness"] < 0.8 * plain["flatness"]
    assert facts["ribbed"]["ribbing"] > 0.15
    assert facts["pointed"]["flatness"] > 1.2 * plain["flatness"]
    for f in facts.values():
        assert all(np.isfinite(list(f.values())))


def test_malformed_fruit_is_a_valid_ball():
    from ramure.gmap.kernel import topology

    for seed in range(4):
        gm = build_fruit("round_tomato", volume_levels=1, seed=seed, **malform_params("round_tomato", rate=1.0, seed=seed))
        topology.assert_solid(gm)


def test_refusals():
    with pytest.raises(ValueRefused, match="unknown malformation"):
        malform_params(shape="wobbly")
    with pytest.raises(ValueRefused, match=r"\[0, 1\]"):
        malform_params(rate=1.5)
    with pytest.raises(ValueRefused, match="stepmax"):
        build_fruit("round_tomato", stepmax=11)
    with pytest.raises(ValueRefused, match="hamp"):
        build_fruit("round_tomato", hamp=-1)
    assert parse_malform("ribbed, rate=0.25") == {"shape": "ribbed", "rate": 0.25}
    for bad, msg in (("rate=x", "not a number"), ("rate=nan", "[0, 1]"), ("size=2", "expected a shape")):
        with pytest.raises(ValueRefused, match=msg.replace("[", r"\[").replace("]", r"\]")):
            parse_malform(bad)


def test_cli_malform(capsys):
    from ramure.app.cli import main

    assert main(["fruit", "--malform", "lopsided,rate=0.2", "--seed", "2", "--json"]) == 0
    rec = json.loads(capsys.readouterr().out)["malformation"]
    assert rec["shape"] == "lopsided" and rec["rate"] == 0.2 and rec["params"]["hamp"] == 1.0
    assert rec["lopsidedness"] > 0.02
    for bad, msg in ((["--malform", "wobbly"], "unknown shape"), (["--malform", "rate=3"], "[0, 1]")):
        assert main(["fruit", *bad]) == 2
        err = capsys.readouterr().err
        assert msg in err and "Traceback" not in err and err.count("\n") == 1
