"""3Gmap L-systems: the ``.g3l`` language (``g3l``), its engine (``engine``) and the
face-level operators a rule applies (``operators``: add a volume on a free face, identify two
faces).  It builds maps through the public API of :mod:`ramure.gmap.kernel` and may import
that kernel, :mod:`ramure.lsys.expr` (the expression language it shares with ``.lsys``),
:mod:`ramure.errors`, :mod:`ramure.io` and :mod:`ramure.grammars`; never
:mod:`ramure.gmap.organs` or the front ends.
"""
