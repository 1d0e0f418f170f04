"""Readers of other tools' grammars that need the whole engine: L-Py (``lpy``: an ``.lpy``
file as an ``LSystem``; ``lpy_translate``: its Python-like rules; ``lpy_plantgl``: the few
PlantGL names such files use).  (cpfg's reader is part of the language: the engine calls
it.)  It may import the engine, the language, the interpretation, the history, the lsys
root modules and ``ramure.<base>``.
"""
