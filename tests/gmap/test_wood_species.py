"""Wood species (pine, larch, elm, oak): bark shedding and roughness, latewood share, colours,
compression and tension wood, whorls, texture, and the solid's invariants."""

import json

import numpy as np
import pytest

from ramure.app.cli import main
from ramure.gmap.organs import wood as W
from ramure.gmap.organs import wood_species as S

SPECIES = ("pine", "larch", "elm", "oak")


@pytest.fixture(scope="module")
def trunks():
    return {name: W.grow_wood(name, years=14, branches=0) for name in SPECIES}


def _stack_bark(w):
    """Per trunk stack (level, sector): wood radius, live bark thickness, fissure flag, shed cells."""
    vd = w.gm.volume_data
    trunk = (vd["axis"] == 0) & (vd["cell"] > 0)
    out = {}
    for lv, sec in set(zip(vd["level"][trunk].tolist(), vd["sector"][trunk].tolist())):
        m = trunk & (vd["level"] == lv) & (vd["sector"] == sec)
        bark = m & (vd["wood"] == W.CODES["bark"])
        marks = vd["bark"][bark]
        wood = float(w.p["pith_radius"] + vd["width"][m & ~bark].sum())
        shed = marks >= S.SHED_PLATE
        out[lv, sec] = (wood, float(vd["width"][bark].sum()), bool(np.isin(marks, [2, 4]).any()), int(shed.sum()))
    return out


@pytest.mark.parametrize("name", SPECIES)
def test_bark_is_shed_to_the_species_thickness(trunks, name):
    w = trunks[name]
    p = w.p
    layers = 14 * p["bark_min"]  # what ten-plus layers would be with nothing shed
    for (lv, _), (wood, bark, fissure, shed) in _stack_bark(w).items():
        cap = min(p["bark_cap"], p["bark_ratio"] * wood) * (p["fissure_depth"] if fissure else 1.0)
        assert bark <= cap + shed * S.SHED_WIDTH + 1e-12
        if 14 - lv >= 8:  # an old stack has shed: its live bark is exactly the cap
            # the live layers fill the cap (one trimmed), the shed ones are SHED_WIDTH thin
            assert shed > 0 and cap + (shed - 1) * S.SHED_WIDTH - 1e-12 <= bark
            assert bark < 0.5 * layers
        assert bark / wood < 0.11  # never a quarter of the radius again
    assert w.gm.euler_characteristic() == 1


@pytest.mark.parametrize("name", SPECIES)
def test_bark_outline_is_rough_plates_or_ridges(trunks, name):
    """The outer radius of the stacks (wood + bark) varies round the trunk: fissures cut into the bark."""
    w = trunks[name]
    stacks = _stack_bark(w)
    level = 2
    fissures = [stacks[level, k][2] for k in range(16)]
    assert 0 < sum(fissures) < 16
    if S.SPECIES[name]["bark_pattern"] == "ridges":  # every other stack round the trunk
        assert fissures[0::2] != fissures[1::2] and len(set(fissures[0::2])) == 1
    outer = [stacks[level, k][0] + stacks[level, k][1] for k in range(16)]
    assert max(outer) - min(outer) > 0.3 * min(s[1] for s in stacks.values() if not s[2])


def test_latewood_share_by_species(trunks):
    shares = {}
    for name, w in trunks.items():
        vd = w.gm.volume_data
        wood = (vd["axis"] == 0) & np.isin(vd["wood"], [W.CODES["sapwood"], W.CODES["heartwood"]])
        late = vd["width"][wood & (vd["season"] == W.LATE)].sum()
        shares[name] = late / vd["width"][wood].sum()
        assert shares[name] == pytest.approx(S.latewood_share(w.p), abs=0.04)
    assert 0.20 <= shares["pine"] <= 0.35 and 0.30 <= shares["larch"] <= 0.45  # [ZOB]
    assert shares["pine"] < shares["larch"] < shares["oak"] < shares["elm"]


def test_species_colours_differ(trunks):
    colours = {}
    for name, w in trunks.items():
        rgb = W.cell_colors(w.gm.volume_data, name)
        heart = w.gm.volume_data["wood"] == W.CODES["heartwood"]
        assert heart.any()
        colours[name] = tuple(rgb[heart].mean(axis=0).round())
    assert len(set(colours.values())) == 4
    red = {n: c[0] - c[2] for n, c in colours.items()}
    assert red["larch"] > red["oak"]  # larch's heartwood is the reddest, oak's the least


@pytest.mark.parametrize(
    ("name", "kind", "sign"),
    [("pine", S.COMPRESSION, -1), ("larch", S.COMPRESSION, -1), ("oak", S.TENSION, 1), ("elm", S.TENSION, 1)],
)
def test_reaction_wood_side(name, kind, sign):
    """Compression wood under a conifer's branch, tension wood over a broadleaf's, in the
    embedded cells: their centres lie below (above) the branch's axis."""
    w = W.grow_wood(name, years=8, branches=[(3, 0)], branch_levels=0)
    vd = w.gm.volume_data
    grid = W.to_grid(w, convex=False)
    vol = np.asarray(grid.cell_data["volume"])
    centres = np.asarray(grid.cell_centers().points)
    _, frame = w.branch_frame(w.branches[0])
    on = (vd["axis"][vol] == 1) & (vd["cell"][vol] > 0) & (vd["level"][vol] >= 1)
    level = vd["level"][vol]
    pith = (vd["axis"][vol] == 1) & (vd["cell"][vol] == 0)
    axis_at = {int(t): centres[pith & (level == t)].mean(axis=0) for t in np.unique(level[on])}  # the bent branch's pith
    d = centres - np.array([axis_at.get(int(t), centres[0]) for t in level])
    up = (d - (d @ frame[0])[:, None] * frame[0])[:, 2]
    marks = vd["reaction"][vol]
    react = on & (marks == kind)
    assert react.any() and not (on & (marks > 0) & (marks != kind)).any()
    assert np.mean(sign * up[react] > 0) > 0.95
    assert sign * up[react].mean() > sign * up[on & (marks == 0)].mean()
    rgb = np.asarray(grid.cell_data["rgb"], float)
    late = on & (vd["season"][vol] == W.LATE)
    darker = rgb[late & react].sum(axis=1).mean() < rgb[late & ~react].sum(axis=1).mean()
    assert darker == (kind == S.COMPRESSION)  # compression wood darker, tension wood paler


def test_trunk_reaction_wood_on_the_wide_side():
    w = W.grow_wood("pine", years=4, branches=0, reaction=0.6, reaction_angle=0)
    vd = w.gm.volume_data
    comp = vd["reaction"] == S.COMPRESSION
    assert comp.any()
    assert set(vd["sector"][comp].tolist()) == {14, 15, 0, 1, 2}
    assert (
        vd["width"][comp & (vd["season"] == W.EARLY)].mean()
        > vd["width"][~comp & (vd["season"] == W.EARLY) & (vd["axis"] == 0)].mean()
    )


def test_branch_patterns():
    p = {name: W.resolve_params(name) for name in SPECIES}
    pine = W.place_branches(p["pine"], years=12, seed=1, count=6)
    years = [b.year for b in pine]
    assert len(set(years)) == 2 and all(years.count(y) == 3 for y in set(years))  # whorls of 3
    larch = W.place_branches(p["larch"], years=12, seed=1, count=5)
    assert len({b.year for b in larch}) == 5  # scattered
    elm = W.place_branches(p["elm"], years=12, seed=1, count=4)
    sectors = [b.sector for b in elm]
    assert sectors[0] == sectors[2] and (sectors[1] - sectors[0]) % 16 == 8  # two ranks
    assert len(W.place_branches(p["pine"], years=10, seed=0, count=144)) == 144
    with pytest.raises(W.ValueRefused):
        W.resolve_params("pine", whorl=0)


@pytest.mark.parametrize("name", SPECIES)
def test_species_with_branches_stay_one_ball(name):
    w = W.grow_wood(name, years=6, check_every_step=True)
    assert w.gm.is_valid() and w.gm.euler_characteristic() == 1 and w.gm.boundary().euler_characteristic() == 2


def test_texture_pores_and_rays():
    rng = np.random.default_rng(0)
    n = 40000
    pts = np.column_stack([rng.uniform(0.01, 0.04, n), rng.uniform(-0.02, 0.02, n), rng.uniform(0, 0.1, n)])
    base = np.full((n, 3), 200, np.uint8)
    wood = np.ones(n, bool)
    early, late = np.full(n, W.EARLY), np.full(n, W.LATE)
    assert (S.EARLY, S.LATE) == (W.EARLY, W.LATE)
    dark = {}
    for name in SPECIES:
        e = S.texture_rgb(name, pts, base, wood, early).astype(int).sum(axis=1)
        la = S.texture_rgb(name, pts, base, wood, late).astype(int).sum(axis=1)
        dark[name] = (np.mean(e < 500), np.mean(la < 500), np.mean(e > 630))  # 630: broad rays are bright, fine ones faint
    assert dark["oak"][0] > 0.05 and dark["elm"][0] > 0.05  # ring-porous earlywood
    assert dark["pine"][0] == 0 and dark["larch"][0] == 0  # no pores in softwoods
    assert dark["pine"][1] > 0 and dark["elm"][1] > 0  # resin canals; elm's latewood bands
    assert dark["oak"][2] > 0.01 and dark["oak"][2] > 3 * dark["elm"][2]  # oak's broad rays
    knot = S.texture_rgb("oak", pts, base, ~wood, early)  # knots, pith and bark stay plain
    assert np.all(knot == base)
    keys = [np.arange(50), 7, np.arange(50) % 3]
    assert np.array_equal(S.u01(*keys), W.u01_array(*keys))  # the wood's own hash


@pytest.mark.parametrize("name", ["larch", "elm"])
def test_cli_species(capsys, name):
    assert main(["wood", "--species", name, "--years", "3", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["species"] == name and (r["chi"], r["boundary_chi"]) == (1, 2)
    assert r["reaction"]["tension" if name == "elm" else "compression"] > 0
    assert r["reaction"]["compression" if name == "elm" else "tension"] == 0
    cap = 1000 * min(W.SPECIES[name]["bark_cap"], W.SPECIES[name]["bark_ratio"] * 0.05)
    assert 0 < r["bark_mm"]["mean"] <= r["bark_mm"]["max"] < cap + 3 * 1000 * S.SHED_WIDTH


@pytest.mark.parametrize("name", ["oak", "elm"])
def test_tension_wood_keeps_a_knot_darker_than_the_wood_round_it(name):
    """A broadleaf's knot with tension wood on its upper side still reads as a knot: each of
    its seasons is darker than the trunk's heartwood and sapwood of that season, yet paler than
    the knot's other side (a 0.35 veil drew oak's and elm's knots half pale grey)."""
    colors = W.SPECIES[name]["colors"]
    rgb = np.array([[int(c[i : i + 2], 16) for i in (1, 3, 5)] for c in colors["knot"]], float)
    veiled = S.reaction_rgb(rgb, np.full(2, S.TENSION)).sum(axis=1)
    for tissue in ("heartwood", "sapwood"):
        trunk = np.array([sum(int(c[i : i + 2], 16) for i in (1, 3, 5)) for c in colors[tissue]], float)
        assert np.all(veiled < trunk)
    assert np.all(veiled > rgb.sum(axis=1))
