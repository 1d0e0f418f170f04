"""The grammar language: ``grammar`` (the ``.lsys`` parser and ``Grammar``), ``cstatements``
(cpfg's C-like statements) and ``cpfg`` (the cpfg ``.l`` reader).  It checks a grammar
against the drawing's vocabulary and AMAP's annotations, so it may import
``ramure.lsys.interpretation``, ``ramure.lsys.architecture``, the lsys root modules
(``errors``, ``expr``: the expression language), ``ramure.grammars`` and ``ramure.<base>``.
"""
