"""The 3-G-map kernel: darts, involutions, orbits, sewing, validity, attributes, cuts and I/O.

It owns :class:`~ramure.gmap.kernel.map3.GMap3` (``map3``: its ``storage`` with the ``operations`` on top, and
the compiled ``_*_kernel`` passes), the labelled prism template (``prism``, ``faces``),
face gluing (``identify``), frames and embedding, orbit graphs (``graphs``), Euler
characteristics (``topology``), incidence, exact volumes (``measure``), attribute
propagation (``attributes``), subdivision, plane cuts (``cut``, ``mapcut``) and conversion to
pyvista (``pyvista``).  It may import numpy, scipy, numba (through :mod:`ramure.jit`),
pyvista data objects and :mod:`ramure.errors`; it never imports
:mod:`ramure.gmap.lsystem`, :mod:`ramure.gmap.organs`, :mod:`ramure.lsys` or the front ends.
"""
