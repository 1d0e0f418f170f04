"""Errors raised by the 3-G-map kernel and the fruit builders.

They derive from :class:`ramure.lsys.errors.RamureError`, so the CLI prints them as a
plain message without a traceback.
"""

from __future__ import annotations

from ramure.errors import RamureError, ValueRefused

__all__ = ["GMapError", "ValueRefused"]


class GMapError(RamureError, ValueError):
    """A topological request that cannot be met (e.g. sewing a face that is not free)."""
