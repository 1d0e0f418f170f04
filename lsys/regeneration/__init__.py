"""Selective regeneration: the minimum cut over the history tree (``mincut``), the re-derivation
of the cut's roots and the editing session (``regen``), and selections by predicate
(``select``).  It may import the engine, the interpretation, the history, the lsys root
modules and ``ramure.<base>``; nothing in ``ramure.lsys`` imports it but the front door.
"""
