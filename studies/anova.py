"""One-way ANOVA with F, F_crit, p and a verdict, and the table check of the thesis.

The thesis tabulates per-image mean ratings (rows = the 27 image points,
columns = grammars) and runs one-way ANOVA *across grammars* (each column is
a group) and *across image points* (each row is a group), comparing F with
F_crit at alpha = 0.05.  :func:`anova_table` does both; :func:`read_table`
reads such a table from a TSV file so published numbers can be re-checked.

>>> r = one_way_anova([[1, 2, 3], [2, 3, 4], [5, 6, 7]])
>>> round(r.F, 3), round(r.F_crit, 3), r.significant
(13.0, 5.143, True)
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from numpy.typing import ArrayLike

import math
import pathlib
import re
from dataclasses import asdict, dataclass

import numpy as np

from ramure.studies.errors import StudyInputError

ROW_LABEL_WORDS = {"", "#", "id", "image", "images", "point", "points", "pick", "no", "n", "n°", "row"}


@dataclass
class AnovaResult:
    """Sums of squares, degrees of freedom, F, F_crit, p and the verdict."""

    F: float
    F_crit: float
    p: float
    alpha: float
    df_between: int
    df_within: int
    ss_between: float
    ss_within: float
    n_groups: int
    n_values: int

    @property
    def significant(self) -> bool:
        return bool(self.F > self.F_crit)

    @property
    def verdict(self) -> str:
        if math.isnan(self.F):
            return "undefined: every value is equal"
        if self.significant:
            return f"significant: F > F_crit, the group means differ (alpha = {self.alpha:g})"
        return f"not significant: F <= F_crit, no evidence the group means differ (alpha = {self.alpha:g})"

    def as_dict(self) -> dict:
        """Plain JSON-ready dict (a non-finite F or p becomes None; see ``verdict``)."""
        out = {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}
        out.update(significant=self.significant, verdict=self.verdict)
        return out


def one_way_anova(groups: Sequence[ArrayLike], alpha: float = 0.05) -> AnovaResult:
    """One-way ANOVA of ``groups`` (sequences of numbers; NaN values are dropped).

    Groups left empty after dropping NaN are ignored.  Refused: fewer than two
    groups, or no more values than groups (no within-group freedom).
    """
    if not 0 < alpha < 1:
        raise StudyInputError(f"alpha must be between 0 and 1, got {alpha!r}")
    clean = [g[~np.isnan(g)] for g in (np.asarray(x, dtype=float).ravel() for x in groups)]
    clean = [g for g in clean if g.size]
    k = len(clean)
    n = sum(g.size for g in clean)
    if k < 2:
        raise StudyInputError(f"ANOVA needs at least two groups with values, got {k}")
    if n <= k:
        raise StudyInputError(f"ANOVA needs more values ({n}) than groups ({k})")
    sizes = np.array([g.size for g in clean], dtype=float)
    means = np.array([g.mean() for g in clean])
    grand = np.concatenate(clean).mean()
    ss_between = float((sizes * (means - grand) ** 2).sum())
    ss_within = float(sum(((g - m) ** 2).sum() for g, m in zip(clean, means)))
    dfb, dfw = k - 1, n - k
    msb, msw = ss_between / dfb, ss_within / dfw
    if msw > 0:
        F = msb / msw
    else:
        F = math.inf if msb > 0 else math.nan
    # scipy.special's F-distribution functions are what scipy.stats.f calls (sf = fdtrc,
    # ppf = fdtri), without scipy.stats' second of import; its edges kept: sf(0) = 1, sf(inf) = 0.
    from scipy.special import fdtrc, fdtri

    p = math.nan if math.isnan(F) else 1.0 if F <= 0 else 0.0 if math.isinf(F) else float(fdtrc(dfb, dfw, F))
    return AnovaResult(
        F=float(F),
        F_crit=float(fdtri(dfb, dfw, 1 - alpha)),
        p=p,
        alpha=alpha,
        df_between=dfb,
        df_within=dfw,
        ss_between=ss_between,
        ss_within=ss_within,
        n_groups=k,
        n_values=n,
    )


def anova_table(table: ArrayLike, alpha: float = 0.05) -> dict:
    """ANOVA across columns (grammars) and across rows (image points) of ``table``.

    ``table`` is 2-D, rows = image points, columns = grammars, NaN = missing.
    Each result is an :class:`AnovaResult` dict, or ``{"error": reason}`` when
    that test cannot be computed (e.g. a single grammar).
    """
    t = np.asarray(table, dtype=float)
    if t.ndim != 2:
        raise StudyInputError(f"expected a 2-D table (rows = image points, columns = grammars), got {t.ndim}-D")
    out = {}
    for key, groups in (("across_grammars", t.T), ("across_image_points", t)):
        try:
            out[key] = one_way_anova(list(groups), alpha).as_dict()
        except StudyInputError as exc:
            out[key] = {"error": str(exc)}
    return out


def _number(cell):
    cell = cell.strip()
    if cell in ("", "NA", "NaN", "nan", "-", "—"):
        return math.nan
    if re.fullmatch(r"[-+]?\d+,\d+", cell):  # decimal comma, as in French spreadsheets
        cell = cell.replace(",", ".")
    return float(cell)


def _is_number(cell):
    try:
        _number(cell)
        return True
    except ValueError:
        return False


def read_table(path: str | os.PathLike, row_labels: bool | None = None) -> tuple[np.ndarray, list[str], list[str]]:
    """Read a TSV table: returns ``(values, row_names, column_names)``.

    Cells are split on tabs (on runs of spaces when the file has no tab); blank
    lines and ``#`` comments are skipped; a decimal comma is accepted; an empty
    cell, ``NA`` or ``-`` is missing.  The first row is a header when any of
    its cells after the first is not a number (or only its first cell is
    text while the first column below is numeric).  The first column holds row labels when
    ``row_labels`` is True, or (when None) when it has a non-number below the
    header, or when the header names it ``image``, ``point``, ``id``, ``#`` or
    leaves it empty.
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise StudyInputError(f"{path}: no such table file")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise StudyInputError(f"{path}: not UTF-8 text (byte {exc.start}); save the table as UTF-8") from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise StudyInputError(f"{path}: the table is empty")
    split = (lambda ln: ln.rstrip("\r\n").split("\t")) if "\t" in text else (lambda ln: ln.split())
    rows = [split(ln) for ln in lines]
    header = None
    first_is_header = any(not _is_number(c) for c in rows[0][1:]) or (
        not _is_number(rows[0][0]) and all(_is_number(r[0]) for r in rows[1:])
    )
    if first_is_header:
        header, rows = rows[0], rows[1:]
    if not rows:
        raise StudyInputError(f"{path}: the table has a header but no rows")
    if row_labels is None:
        row_labels = any(not _is_number(r[0]) for r in rows) or (
            header is not None and len(header) == len(rows[0]) and header[0].strip().casefold() in ROW_LABEL_WORDS
        )
    names = [r[0].strip() for r in rows] if row_labels else [str(i + 1) for i in range(len(rows))]
    body = [r[1:] for r in rows] if row_labels else rows
    width = max(len(r) for r in body)
    values = np.full((len(body), width), np.nan)
    for i, r in enumerate(body):
        for j, cell in enumerate(r):
            try:
                values[i, j] = _number(cell)
            except ValueError:
                line = i + 1 + (header is not None)
                raise StudyInputError(
                    f"{path}: row {line}, column {j + 1 + bool(row_labels)}: {cell.strip()!r} is not a number"
                ) from None
            if np.isinf(values[i, j]):
                line = i + 1 + (header is not None)
                raise StudyInputError(
                    f"{path}: row {line}, column {j + 1 + bool(row_labels)}: {cell.strip()!r} is not a finite number"
                )
    if header is not None:
        columns = (
            [c.strip() for c in header[-width:]]
            if len(header) >= width
            else [c.strip() for c in header] + [f"column {j + 1}" for j in range(len(header), width)]
        )
    else:
        columns = [f"column {j + 1}" for j in range(width)]
    return values, names, columns
