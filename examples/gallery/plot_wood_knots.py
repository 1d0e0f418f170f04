"""
Round knots in sawn pine
========================

A 12-year pine grown on a 3D generalized map, with branches of as many sides as the trunk
(16), sawn three ways through its largest knot: a flat-sawn board (the plane misses the pith:
arches, and a round knot that the rings flow round), a quarter-sawn board (the plane holds the
pith: the knot is a spike rising from it) and a cross-cut through the knot (its rings meet the
trunk's). The boards are drawn face-on, as ``ramure wood --plank ... -o plank.png`` draws them.
"""

import numpy as np

from ramure.app.commands.wood import legend_for, render_plank
from ramure.gmap.organs import wood as W

from _show import show

wood = W.grow_wood("pine", years=12, branches=[(3, 0), (5, 6), (7, 11)], height=0.3)
grid = W.smooth_grid(wood, W.to_grid(wood))  # rings drawn with 64 sides
base, frame = wood.branch_frame(wood.branches[0], knot=True)  # the knot faces +x from the pith
radius = wood.trunk_radius()
legend = legend_for("pine")


def board(normal, offset, thickness=0.004, length=4 * radius):
    """A slab of the wood, ``length`` long around its largest knot (cross-cuts: the whole section)."""
    slab = W.plank(grid, normal, offset, thickness)
    if abs(normal[2]) > 0.5:
        return slab
    return W.plank_window(slab, length)[0]


def flat_sawn(path):
    offset = 0.5 * radius
    title = f"flat-sawn, {100 * offset:.1f} cm from the pith"
    render_plank(board((1.0, 0.0, 0.0), offset), path, (1, 0, 0), title=title, legend=legend)


def quarter_sawn(path):
    render_plank(board((0.0, 1.0, 0.0), -0.002), path, (0, 1, 0), title="quarter-sawn, through the pith", legend=legend)


def cross_cut(path):
    height = float(base[2] + 0.5 * radius * frame[0][2] / max(frame[0][0], 1e-9))  # the knot halfway out
    render_plank(board((0.0, 0.0, 1.0), height), path, np.array([0.0, 0.0, 1.0]), title="cross-cut through the knot")


show(flat_sawn)
show(quarter_sawn)
show(cross_cut)
