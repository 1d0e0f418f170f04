"""cpfg's user-defined functions, ``func(id, x)``: B-spline functions from ``.func`` files.

cpfg's view file (``plant.v``) names them, and the order of its lines gives their ids, from 1:

``function: internode.func 100``
    one function (a ``.func`` file, made with funcedit); the number is ignored for the
    ``fver 1 1`` files funcedit writes (their own ``samples:`` line counts), as cpfg does.
``function set: functions.fset``
    a set of functions (gallery); it replaces the functions named before it, and each
    function's name becomes a constant holding its id (``func(LEAF_GROWTH, t)``), as cpfg's
    ``-D NAME=id``.

A function is a cubic B-spline through its control points, uniform and clamped (cpfg's
``SplineFunction::P``: knots 0,0,0,0,1,...,n-2,n-2,n-2,n-2; a point written with a third
number is repeated that many times).  ``func(id, x)`` is the curve's y where its x is ``x``
(``x`` clamped to [0, 1]); cpfg finds that point by bisection to 0.001 in x, precomputes
``samples`` values evenly spaced in [0, 1] and interpolates linearly between them.  Ramure
does the same; a function with no samples (cpfg computes it exactly at each call) is
tabulated at :data:`EXACT_SAMPLES` points.

Which view file: the one with the ``.l`` file's own name (``plant.v`` for ``plant.l``), else
the only ``.v`` file of its folder.  Every file read lies in the ``.l`` file's folder
(:func:`ramure.lsys.language.grammar.confinement_root`, links and ``..`` resolved) and is a
regular file; anything else is refused with the view file's line.

>>> points = [(0.0, 0.0), (1/3, 1/3), (2/3, 2/3), (1.0, 1.0)]   # the straight line y = x
>>> round(float(tabulate(points, 11)[3]), 2)   # within cpfg's 0.001
0.3
"""

from __future__ import annotations

import os
import pathlib
import re
from collections.abc import Sequence

import numpy as np

from ramure.io import FileRefused, read_regular

from ..errors import GrammarError
from ..expr import Tables

#: Values tabulated for a function cpfg computes exactly at each call.
EXACT_SAMPLES = 1025
#: cpfg's bisection stops when the curve's x is this close to the x asked for.
TOLERANCE = 0.001
#: The largest view, function or function-set file read (bytes).
MAX_FILE_BYTES = 4_000_000
_VIEW_LINE = re.compile(r"^[ \t]*function([ \t]+set)?[ \t]*:[ \t]*(\S+)[ \t]*(\S*)", re.I | re.M)


def basis(points: int, u: np.ndarray) -> np.ndarray:
    """(len(u), points) cubic B-spline basis values at parameters ``u`` in [0, points - 3],
    with cpfg's clamped uniform knots."""
    n, order = points - 1, 4
    knots = np.array([0 if j < order else (n - order + 2 if j > n else j - order + 1) for j in range(n + order + 1)], float)
    u = np.asarray(u, float)[:, None]
    values = ((knots[:-1] <= u) & (u < knots[1:])).astype(float)  # order 1
    for t in range(2, order + 1):
        width = knots[t - 1 : t - 1 + len(values[0]) - 1] - knots[: len(values[0]) - 1]
        after = knots[t : t + len(values[0]) - 1] - knots[1 : len(values[0])]
        left = np.divide(u - knots[: len(values[0]) - 1], width, out=np.zeros((len(u), len(width))), where=width != 0)
        right = np.divide(knots[t : t + len(values[0]) - 1] - u, after, out=np.zeros((len(u), len(after))), where=after != 0)
        values = left * values[:, :-1] + right * values[:, 1:]
    return values


def curve_points(points: Sequence[tuple[float, float]], d: np.ndarray) -> np.ndarray:
    """(len(d), 2) points of the curve at ``d`` in [0, 1) (cpfg's ``P(d)``, u = d (n - 2))."""
    control = np.asarray(points, float)
    return basis(len(control), np.asarray(d, float) * (len(control) - 3)) @ control


def tabulate(points: Sequence[tuple[float, float]], samples: int) -> np.ndarray:
    """The function's values at ``samples`` x evenly spaced in [0, 1], found as cpfg finds
    them: bisection on the curve parameter until x is within :data:`TOLERANCE`."""
    want = np.linspace(0.0, 1.0, samples)
    low, high = np.zeros(samples), np.ones(samples)
    found = np.full(samples, np.nan)
    for _ in range(60):  # cpfg loops until close; a curve that never reaches x stops here
        check = (low + high) / 2
        x, y = curve_points(points, check).T
        close = np.isnan(found) & (np.abs(x - want) <= TOLERANCE)
        found[close] = y[close]
        high = np.where(x > want, check, high)
        low = np.where(x > want, low, check)
        if not np.isnan(found).any():
            break
    return np.where(np.isnan(found), y, found)


def read_func(text: str, where: str) -> tuple[str, int, list[tuple[float, float]], int]:
    """(name, samples, control points, lines read) of one function at the start of ``text``
    (``fver 1 1`` or the older ``range:`` format)."""
    lines = text.split("\n")
    head = lines[0].strip() if lines else ""

    def bad(what: str, k: int) -> GrammarError:
        source = lines[k] if k < len(lines) else ""
        return GrammarError(f"cannot read the cpfg function file: {what}", k + 1, 1, source, filename=where)

    k, name, samples = 1, pathlib.Path(where).stem, 0
    if head.startswith("range:"):
        pass
    elif re.fullmatch(r"fver\s+1\s+1", head):
        fields: dict[str, str] = {}
        while k < len(lines) and not lines[k].strip().startswith("points:"):
            key, _, value = lines[k].partition(":")
            fields[key.strip()] = value.strip()
            k += 1
        name = fields.get("name", name)
        try:
            samples = int(fields.get("samples", "0"))
        except ValueError:
            raise bad("'samples:' is not a whole number", 2) from None
    else:
        raise bad("expected 'fver 1 1' or 'range:' on its first line", 0)
    m = re.match(r"\s*points:\s*(\d+)", lines[k]) if k < len(lines) else None
    if not m or int(m.group(1)) < 4:
        raise bad("expected 'points: N' with at least 4 points", k)
    points: list[tuple[float, float]] = []
    for j in range(k + 1, k + 1 + int(m.group(1))):
        words = lines[j].split() if j < len(lines) else []
        try:
            x, y, times = float(words[0]), float(words[1]), int(float(words[2])) if len(words) == 3 else 1
        except (ValueError, IndexError):
            raise bad("expected a point 'x y' or 'x y multiplicity'", j) from None
        points += [(x, y)] * max(times, 1)
    return name, samples, points, k + 1 + int(m.group(1))


def function_values(text: str, where: str, samples: int = -1) -> tuple[str, np.ndarray]:
    """(name, values at evenly spaced x in [0, 1]) of a ``.func`` file's text; ``samples`` is
    the view file's count, used by the older ``range:`` format only."""
    name, own, points, _ = read_func(text, where)
    count = own if text.lstrip().startswith("fver") else samples
    return name, tabulate(points, count if count > 2 else EXACT_SAMPLES)


def function_set(text: str, where: str) -> list[tuple[str, np.ndarray]]:
    """The functions of a ``.fset`` file (``funcgalleryver 1 1``, ``items: N``, then N functions)."""
    lines = text.split("\n")
    if not re.fullmatch(r"funcgalleryver\s+1\s+1", lines[0].strip()) or len(lines) < 2:
        raise GrammarError("cannot read the cpfg function set: expected 'funcgalleryver 1 1'", 1, 1, lines[0], filename=where)
    m = re.match(r"\s*items:\s*(\d+)", lines[1])
    if not m:
        raise GrammarError("cannot read the cpfg function set: expected 'items: N'", 2, 1, lines[1], filename=where)
    out, at = [], 2
    for _ in range(int(m.group(1))):
        rest = "\n".join(lines[at:])
        name, samples, points, used = read_func(rest, where)
        out.append((name, tabulate(points, samples if samples > 2 else EXACT_SAMPLES)))
        at += used
    return out


def view_file(l_file: str | os.PathLike) -> pathlib.Path | None:
    """The view file of a cpfg ``.l`` file: same name with ``.v``, else the only ``.v`` beside it."""
    path = pathlib.Path(l_file)
    same = path.with_suffix(".v")
    if same.is_file():
        return same
    others = sorted(path.parent.glob("*.v"))
    return others[0] if len(others) == 1 else None


def view_tables(l_file: str | os.PathLike, root: pathlib.Path) -> tuple[Tables | None, dict[str, float]]:
    """(the functions ``func`` reads, {function-set name: id}) named by the view file of
    ``l_file``; (None, {}) when it has none.  Files are read only inside ``root``."""
    view = view_file(l_file)
    if view is None:
        return None, {}
    text = read_confined(view, root, None)
    functions: list[tuple[str, np.ndarray]] = []
    names: dict[str, float] = {}
    for m in _VIEW_LINE.finditer(text):
        line = text[: m.start()].count("\n") + 1
        where = (str(view), line, text.split("\n")[line - 1])
        body = read_confined(view.parent / m.group(2), root, where)
        if m.group(1):  # a function set replaces what came before; its names become constants
            functions = function_set(body, str(view.parent / m.group(2)))
            names = {name.rsplit(".", 1)[0]: float(k) for k, (name, _) in enumerate(functions, start=1)}
        else:
            samples = int(m.group(3)) if m.group(3).lstrip("-").isdigit() else -1
            functions.append(function_values(body, str(view.parent / m.group(2)), samples))
    if not functions:
        return None, {}
    return Tables(tuple(tuple(float(v) for v in values) for _, values in functions)), names


def read_confined(path: pathlib.Path, root: pathlib.Path, where: tuple | None) -> str:
    """A file's text (Latin-1, as cpfg's files are), refused unless it is a regular file inside
    ``root``; the refusal names ``where`` (file, line, source line) when given, else the file."""
    resolved = path.resolve()
    try:
        if not resolved.is_relative_to(root):
            raise FileRefused("cpfg file", path, f"it lies outside the grammar's folder {root}")
        return read_regular(resolved, MAX_FILE_BYTES, "cpfg file").decode("latin-1")
    except FileRefused as exc:
        filename, line, source = where if where else (str(path), None, None)
        message = f"cannot read {path.name}: {exc.reason}"
        raise GrammarError(message, line, 1 if line else None, source, filename=filename) from None
