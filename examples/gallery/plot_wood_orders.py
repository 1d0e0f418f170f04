"""
Knots of every order: a branch's branch in its wood
===================================================

The wood of the ABOP tree (``abop_tree``, 6 derivation steps, 10 years, whole branches:
``branch_levels=0``): its first-order branches are knots in the trunk, and each of their
branches a knot in their wood, born in the year the derivation made it, down to the fifth order.
A board sawn along a first-order branch through its first second-order branch shows that
branch leaving its host's pith, its rings running into the host's; a cross-cut of the host a
few millimetres past the knot's base shows the host's round rings and the knot as a spike from
its pith to its bark, the host's rings bending round it, as in a cross-cut of a trunk.
"""

import numpy as np

from ramure.gmap.organs import wood as W
from ramure.lsys import LSystem

from _show import show

d = LSystem.from_file("abop_tree").derive(n=6)
wood = W.from_skeleton(d.skeleton(), 10, leaf_steps=d.tree.step, steps=d.n, branch_levels=0)
print(wood.knot_orders())  # knots by order: in the trunk, in first-order branches, ...
grid = W.smooth_grid(wood, W.to_grid(wood))  # rings drawn with 64 sides
sub = next(b for b, br in enumerate(wood.branches) if br.parent >= 0 and wood.branches[br.parent].parent < 0)
host = wood.branches[sub].parent
(_, host_frame), (base, sub_frame) = wood.branch_frame(wood.branches[host]), wood.branch_frame(wood.branches[sub])
normal = np.cross(host_frame[0], sub_frame[0])  # the plane of both branches' axes
normal /= np.linalg.norm(normal)


def branches_only(part, below=0.02, above=0.04):
    """The host's and the sub-branch's cells, clipped to ``below`` .. ``above`` along the host
    from the knot's base."""
    axis = np.asarray(part.cell_data["axis"])
    part = part.extract_cells(np.flatnonzero(np.isin(axis, [host + 1, sub + 1])))
    h = host_frame[0]
    part = part.clip(normal=tuple(-h), origin=tuple(base - below * h))
    return part.clip(normal=tuple(h), origin=tuple(base + above * h))


def render(part, path, look, up):
    """The part face-on (looking along ``look``), ``up`` up, unlit: the tissues' colours."""
    from ramure.app.render import headless_setup

    headless_setup()
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True, window_size=(900, 900))
    plotter.add_mesh(part, scalars="rgb", rgb=True, lighting=False)
    plotter.camera.focal_point = part.center
    plotter.camera.position = np.asarray(part.center) - 0.2 * np.asarray(look)
    plotter.camera.up = tuple(up)
    plotter.enable_parallel_projection()
    plotter.reset_camera()
    plotter.screenshot(path)
    plotter.close()


def along_the_host(path):
    slab = W.plank(grid, normal, float(normal @ base) - 0.002, 0.004)
    render(branches_only(slab), path, -normal, host_frame[0])


def across_the_host(path):
    cut = grid.slice(normal=host_frame[0], origin=base + 0.004 * host_frame[0])
    render(branches_only(cut), path, host_frame[0], normal)


show(along_the_host)
show(across_the_host)
