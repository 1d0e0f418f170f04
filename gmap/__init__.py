"""3-G-maps and volumetric fruit, in three rooms.

- :mod:`ramure.gmap.kernel`: the 3-G-map itself (:class:`GMap3`: darts and involutions as
  numpy arrays), its operations, orbits, validity, attributes, subdivision, cuts and
  conversion to pyvista;
- :mod:`ramure.gmap.lsystem`: the ``.g3l`` language (3Gmap L-systems) and its engine;
- :mod:`ramure.gmap.organs`: the biology built on both: wood, fruit, tissues, defects,
  excrescences, cracks and lichen.

Fruit are built by :func:`ramure.gmap.organs.fruit.build_fruit`; subdivision lives in
:mod:`ramure.gmap.kernel.subdivide`, tissues in :mod:`ramure.gmap.organs.tissue`, conversion to
pyvista in :mod:`ramure.gmap.kernel.pyvista` and plane cuts in :mod:`ramure.gmap.kernel.cut`.

>>> from ramure.gmap import GMap3
>>> gm = GMap3()
>>> _ = gm.add_prisms(4)
>>> gm.counts()["darts"]
48
"""

from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.kernel.map3 import GMap3
from ramure.gmap.kernel.storage import sublabel_name
from ramure.gmap.kernel.prism import face_label_code, face_label_name
from ramure.gmap.kernel import cut, subdivide  # noqa: E402  (gmap.kernel.pyvista: import it yourself)
from ramure.gmap.organs import fruit, plant, tissue

__all__ = [
    "GMap3",
    "GMapError",
    "cut",
    "face_label_code",
    "face_label_name",
    "fruit",
    "plant",
    "subdivide",
    "sublabel_name",
    "tissue",
]
