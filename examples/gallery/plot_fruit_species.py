"""
Fruit species and ripeness
==========================

Every fruit preset at three ripeness stages (apples at their four colours): tomatoes from
green to red, an apple, a pear, a banana from green to yellow with brown flecks, a plum and a
cherry. Each picture is framed by its fruit's real size, written under it (cherry tomato
25 mm, banana 180 mm), and its PNG carries the millimetres per pixel. One of them:
``ramure fruit --preset banana --ripeness flecked -o b.png``.
"""

from ramure.app.fruit_gallery import species_sheet

from _show import show


def sheet(path):
    species_sheet(path, tile=220)


show(sheet)


# %%
# Inside, cut along the axis (twice subdivided): a tomato's locules and seeds, an apple's and a
# pear's core with their pips, a banana's pulp round its placenta, the stone of a plum and of a
# cherry. Legends name the tissues as each species has them.

from ramure.app.fruit_gallery import inside_sheet  # noqa: E402


def cut_sheet(path):
    inside_sheet(path, tile=240)


show(cut_sheet)
