"""The turtle and the geometry it draws: ``turtle`` (the skeleton and organs of a module
string, compiled walk in ``_turtle_kernel``, plain walk in ``_turtle_walk``), its vocabulary
(``actions``), ``polygons`` (the leaves drawn between ``{`` and ``}``), ``surfaces`` and
``materials`` (``#surface`` and ``#material`` templates and their directive parsers), meshes
(``geometry``) and ``homomorphism`` (interpretation-time rules).  It reads module strings and
history trees, not grammars: it may import ``ramure.lsys.history``, the lsys root modules and
``ramure.<base>``.
"""
