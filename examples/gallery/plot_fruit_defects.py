"""
Fruit defects graded by the UNECE standards
===========================================

Each defect class twice, a better and a worse case side by side, with the UNECE class
computed from the measured defect (``ramure.gmap.organs.grading``): a healed crack on an apple
(FFV-50: Class I up to 2 cm, Class II up to 4 cm), a crack round a tomato's stem scar (FFV-36:
no crack in Class I; healed, Class II; fresh, out of grade), hail (round pits, a corky scar
in a bowl with a bruised rim), shrivel (wrinkled skin), an excrescence and rot (a round lesion:
browning, a water-soaked rim, mould colonies; out of grade in every class).
"""

from ramure.app.fruit_gallery import defect_sheet

from _show import show


def sheet(path):
    defect_sheet(path, tile=240)


show(sheet)
