"""Plant architecture around the L-system: AMAP's tables and event schedule (``amap``,
``schedule``), MTG files read and written (``mtg``, ``mtg_graph``, ``mtg_plant``) and the
seasons (``seasons``).  They describe plants as data, not as derivations, so this room may
import only the lsys root modules (``ramure.lsys.errors``, ``ramure.lsys.expr``) and
``ramure.<base>``; the language (``#amap`` annotations) and the engine (MTG grammars) import it.
"""
