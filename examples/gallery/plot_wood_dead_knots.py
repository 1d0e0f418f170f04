"""
Live and dead knots in sawn pine
================================

A 12-year pine with two branches on one side: the lower one, born in year 3, lives; the one above
it, born in year 4, dies in year 7 (``grow_wood(branch_deaths={1: 7})``; ``--set branch_life=N``
kills every branch N years after its birth). A cross-cut through each knot shows the difference a
sawyer looks for: the live knot's rings run into the trunk's (an intergrown, tight knot), while the
dead knot keeps its bark as a dark ring and the trunk's later rings wrap round it (an encased,
loose knot). A flat-sawn board through the dead knot shows the same black ring on its face. A
radial cut along the dead branch shows its occlusion: the rings laid after its death run up the
stub and close over its end, so the dead knot is buried in the wood (``Wood._cap_stub``).

A dead branch's knot is encased only outside the radius the trunk had when the branch died (here
about 0.34 of the final radius): inside it the wood grew round a live branch, and the knot is
intergrown there too (a "sound knot" near the pith, a "loose knot" outside; Moberg 2001, *Forest
Ecology and Management* 147). So the cuts cross the dead knot in its loose part: its cross-cut four
fifths of the way out along it (a horizontal cut runs a long way along a rising knot; the live
knot's is half-way out), the board 0.55 of the radius from the pith.
"""

import numpy as np

from ramure.app.commands.wood import legend_for, render_plank
from ramure.gmap.organs import wood as W

from _show import show

wood = W.grow_wood("pine", years=12, branches=[(3, 0), (4, 1)], branch_deaths={1: 7}, height=0.3)
grid = W.smooth_grid(wood, W.to_grid(wood))  # rings drawn with 64 sides
radius = wood.trunk_radius()
legend = legend_for("pine")


def knot_height(b, out):
    """Height of branch ``b``'s knot pith ``out`` (a share of the trunk's radius) from the pith."""
    base, frame = wood.branch_frame(wood.branches[b], knot=True)
    return float(base[2] + out * radius * frame[0][2] / max(np.hypot(frame[0][0], frame[0][1]), 1e-9))


def cross_cut(b, path):
    state = "dead" if b in wood.dead else "live"
    slab = W.plank(grid, (0.0, 0.0, 1.0), knot_height(b, 0.8 if b in wood.dead else 0.5), 0.004)
    render_plank(slab, path, np.array([0.0, 0.0, 1.0]), title=f"cross-cut through the {state} knot")


def flat_sawn_dead(path):
    offset = 0.55 * radius
    slab = W.plank(grid, (1.0, 0.0, 0.0), offset, 0.004)
    part = W.plank_window(slab, 3 * radius, at=knot_height(1, 0.55))[0]
    title = f"flat-sawn, {100 * offset:.1f} cm from the pith: the dead knot"
    render_plank(part, path, (1, 0, 0), title=title, legend=legend)


def along_dead_stub(path):
    phi = 2 * np.pi * wood.branches[1].sector / wood.trunk.sides
    normal = np.array([-np.sin(phi), np.cos(phi), 0.0])  # the plane holds the trunk's axis and the branch
    slab = W.plank(grid, normal, -0.002, 0.004)
    part = W.plank_window(slab, 6 * radius, at=knot_height(1, 1.6))[0]
    render_plank(part, path, normal, title="radial cut along the dead branch: later rings close over its stub", legend=legend)


show(cross_cut, 0)
show(cross_cut, 1)
show(flat_sawn_dead)
show(along_dead_stub)
