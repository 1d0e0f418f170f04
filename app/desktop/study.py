"""Study mode (placeholder while the screens are written)."""
from __future__ import annotations


class StudyMenu:
    def __init__(self, window, menu):
        self.window = window
        self.menu = menu
