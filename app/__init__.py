"""Ramure front ends: the ``ramure`` command line, the desktop window, Jupyter widgets.

Thin layers over :mod:`ramure.lsys`, :mod:`ramure.metrics`, :mod:`ramure.gmap` and :mod:`ramure.studies`.
"""
