"""Ramure front ends: the ``ramure`` command line, the desktop window, Jupyter widgets.

Thin layers over :mod:`lsys`, :mod:`metrics`, :mod:`gmap` and :mod:`studies`.
"""
