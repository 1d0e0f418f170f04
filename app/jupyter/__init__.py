"""Ramure in Jupyter (ipywidgets 8, JupyterLab 4): the explorer, study sessions, the study report.

>>> from ramure.app.jupyter import NotebookExplorer
>>> ex = NotebookExplorer("grammars/honda_sympodial.lsys", n=4, view="static")
>>> len(ex.plant) > 0, ex.selection, ex.history
(True, [], [])

Display ``ex`` in a cell to get the widgets; everything they do is also a
method (``ex.select``, ``ex.regrow``, ``ex.explore_variants``...).
"""

from ramure.app.jupyter._ui import side_by_side
from ramure.app.jupyter.explorer import NotebookExplorer
from ramure.app.jupyter.report import report_html, show_report
from ramure.app.jupyter.study import StudyPanel

__all__ = ["NotebookExplorer", "StudyPanel", "report_html", "show_report", "side_by_side"]
