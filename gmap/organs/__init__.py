"""The biology built on the 3-G-map: wood (``wood``), fruit (``fruit``, ``plant``, ``malform``,
``tissue``), fruit defects and excrescences (``defects``, ``excrescence``) and surface details
(``cracks``, ``mapcracks``, ``lichen`` on a ``trimesh``).  It may import
:mod:`ramure.gmap.kernel`, :mod:`ramure.gmap.lsystem` (wood grows from a ``.g3l`` grammar),
:mod:`ramure.lsys` (turtle frames of a derived plant), numpy, scipy, manifold3d and
:mod:`ramure.errors`; never the front ends.
"""
