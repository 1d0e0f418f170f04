"""The window's bridge to :mod:`ramure.metrics`: explorations, the 27 picks, qualifiers (no Qt).

A :class:`VariantSet` is what the gallery, the PCA dock and the qualifier
drop-down show: the 27 picks (``picks.json`` records), the PCA cloud and,
when a fitted sweep is at hand, the qualifier vocabulary with one box per
qualifier in PCA space.  It comes from :func:`explore_plant` (runs the sweep,
cancellable, with progress) or :func:`load_exploration` (a directory written
by ``ramure explore`` / :func:`ramure.metrics.write_exploration`).

Ramure's own packages are imported directly: a missing one is a broken install, not a
feature to hide.
"""

from __future__ import annotations

import csv
import io
import os
import pathlib
import threading
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ramure.errors import RamureError

if TYPE_CHECKING:
    from ramure.lsys import LSystem
    from ramure.lsys.interpretation.turtle import Skeleton
    from ramure.metrics.apply import QualifierResult
    from ramure.metrics.exploration import Exploration


@dataclass
class VariantSet:
    """The 27 picks, the cloud and (optionally) the qualifiers of one grammar's exploration."""

    name: str
    picks: list  # picks.json records: {"id", "variant", "pca", "params", "image"?}
    points: np.ndarray | None = None  # (N, 3) PCA cloud
    n: int | None = None
    seed: int = 0
    exploration: Exploration | None = None  # when explored in this window
    boxes: dict = field(default_factory=dict)  # qualifier -> (lo (3,), hi (3,)) in PCA space
    directory: pathlib.Path | None = None

    @property
    def qualifiers(self) -> list[str]:
        """Qualifier names offered in the drop-down (empty without a fitted sweep)."""
        if self.exploration is None:
            return []
        vocab = _vocabulary()
        return list(vocab) if vocab else []

    def image_path(self, pick: Mapping[str, Any]) -> pathlib.Path | None:
        """The picture file of ``pick`` (relative to the exploration folder), None when it has none."""
        image = pick.get("image")
        if not image:
            return None
        path = pathlib.Path(image)
        if not path.is_absolute() and self.directory is not None:
            path = self.directory / path
        return path if path.is_file() else None


def metrics_available() -> str | None:
    """None: :mod:`ramure.metrics` is part of Ramure (kept so the docks can say why a feature is
    off, should one ever depend on an optional package)."""
    return None


def _vocabulary():
    from ramure.metrics.qualifiers import VOCABULARY

    return VOCABULARY


def vocabulary_names() -> list[str]:
    """The qualifier vocabulary (English names), or [] without :mod:`ramure.metrics.qualifiers`."""
    return list(_vocabulary())


def accepted_words(extra: Iterable[str] = ()) -> list[str]:
    """Every word the qualifier box completes to (:func:`ramure.metrics.words.typed_words`,
    as in every front end), with ``extra`` canonical words (a study's)."""
    from ramure.metrics.words import typed_words

    return typed_words(extra)


def qualifier_key(text: str, extra: Iterable[str] = ()) -> str:
    """The canonical qualifier a typed ``text`` names, or a refusal naming the nearest words
    (:func:`ramure.metrics.qualifiers.vocabulary_name`); ``extra``: a study's words."""
    from ramure.metrics.qualifiers import vocabulary_name

    return vocabulary_name(text, extra=extra)


def read_study_words(path: str | os.PathLike) -> dict[str, dict]:
    """``{word: entry}`` of a vocabulary file written by ``ramure study words``."""
    from ramure.metrics.words import read_words_file

    return read_words_file(path)


def qualifier_meanings() -> dict[str, str]:
    """``{name: "dense (FR dense): more branches per unit of box volume"}`` for tooltips."""
    return {name: f"{name} (FR {q.french}): {q.meaning}" for name, q in _vocabulary().items()}


def explore_plant(
    lsystem: LSystem,
    n: int | None,
    seed: int,
    progress: Callable[[int, int], None] | None = None,
    cancel: threading.Event | Callable[[], bool] | None = None,
    n_jobs: int | None = None,
    hidden: bool = False,
    wide: float | None = None,
) -> VariantSet:
    """Sweep ``lsystem``'s variants, run the PCA and pick 27 (see :func:`ramure.metrics.explore`).

    ``hidden`` also varies the grammar's hidden constants (literals, rule probabilities) and
    ``wide`` adds a larger step (e.g. 0.25), as ``ramure explore --hidden --wide``; both off by
    default, so the default cloud is the thesis's ±10 % sweep of the ``#define`` constants.
    """
    reason = metrics_available()
    if reason:
        raise RamureError(reason)
    from ramure.metrics import VariantSweep, explore

    sweep = VariantSweep(n=n, seed=seed, n_jobs=n_jobs, mp_context="forkserver", hidden=hidden, wide=wide)
    exp = explore(lsystem, progress=progress, cancel=cancel, sweep=sweep)
    picks = exp.pick_records()
    name = exp.name
    filename = getattr(lsystem.grammar, "filename", None)
    if filename:
        name = pathlib.Path(filename).stem
    return VariantSet(name, picks, np.asarray(exp.points, float), exp.sweep.n_, seed, exp, qualifier_boxes(exp))


def qualifier_boxes(exploration: Exploration, per_qualifier: int = 10) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """One PCA-space box per vocabulary qualifier: around its ``per_qualifier`` best variants."""
    from ramure.metrics.qualifiers import QualifierRegions, ranked_variants

    points = {}
    for name in _vocabulary():
        try:
            order, _ = ranked_variants(name, exploration.sweep)
        except RamureError:
            continue
        pts = exploration.points[order[:per_qualifier]]
        pts = pts[np.all(np.isfinite(pts), axis=1)]
        if len(pts):
            points[name] = pts
    if not points:
        return {}
    regions = QualifierRegions(trim=0.0).fit(points)
    return {k: (np.asarray(lo), np.asarray(hi)) for k, (lo, hi) in regions.boxes_.items()}


def load_exploration(directory: str | os.PathLike) -> VariantSet:
    """Read an exploration directory: ``picks.json`` (required, read by :func:`ramure.studies.load_picks`),
    ``variants.csv`` (the cloud) and ``pca.json`` (grammar name, n, seed: read by
    :func:`ramure.metrics.exploration.read_exploration_info`)."""
    from ramure.metrics.exploration import read_exploration_info
    from ramure.studies import load_picks

    directory = pathlib.Path(directory)
    picks = [
        {"id": p.id, "variant": p.variant, "pca": list(p.pca), "params": p.params, **({"image": p.image} if p.image else {})}
        for p in load_picks(directory)
    ]
    info = read_exploration_info(directory)  # checked: a value of the wrong type is refused in one line
    points = _cloud(directory / "variants.csv")
    return VariantSet(info.name, picks, points, info.n, info.seed, directory=directory)


#: Largest ``variants.csv`` read (bytes): a sweep of 100,000 variants is about 60 MB.
MAX_VARIANTS_CSV_BYTES = 256 << 20


def _cloud(path):
    from ramure.io import read_regular

    if not path.exists():
        return None
    data = read_regular(path, MAX_VARIANTS_CSV_BYTES, "variants file")  # no pipe, no device, bounded
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise RamureError(f"{path}: not UTF-8 text (byte {exc.start})") from None
    rows = []
    for row in csv.DictReader(io.StringIO(text, newline="")):
        try:
            rows.append([float(row["pc1"]), float(row["pc2"]), float(row["pc3"])])
        except (KeyError, TypeError, ValueError):  # a missing column, a short row, not a number
            rows.append([np.nan] * 3)
    return np.asarray(rows, float) if rows else None


#: Short names of the metrics in status messages ("dense: density 1772 → 2172").
METRIC_LABELS = {
    "box_volume": "box volume",
    "box_surface": "box surface",
    "branch_surface": "bark area",
    "branch_volume": "wood volume",
    "branch_density": "density",
    "branch_count": "branches",
    "fill_rate": "fill rate",
    "total_length": "total length",
    "mean_length": "mean length",
    "mean_radius": "mean radius",
}


def qualifier_message(result: QualifierResult) -> str:
    """One status-bar line for a :class:`ramure.metrics.apply.QualifierResult`.

    Names the metric that weighs most in the qualifier's direction and its
    value on the selection before and after, e.g. ``dense: density 1772 → 2172``.
    """
    name = result.qualifier
    vocab = _vocabulary()
    direction = getattr(vocab.get(name), "direction", None)
    tries = f" ({result.tried} tries)" if result.tried > 1 else ""
    why = f": {result.reason}" if getattr(result, "reason", None) else ""
    if not direction and getattr(result, "regen", True) is None:  # a study's word that moved nothing
        return f"{name}: no variant moved the selection that way{tries}; the plant is as it was{why}"
    if not direction:
        return f"{name}: applied variant {result.variant} (rule {result.params.get('rule')}){tries}"
    metric = max(direction, key=lambda k: (abs(direction[k]), _relative_change(result, k)))
    before, after = getattr(result.before, metric), getattr(result.after, metric)
    change = f"{METRIC_LABELS.get(metric, metric)} {_short(before)} → {_short(after)}"
    if result.improved:
        return f"{name}: {change}{tries}"
    return f"{name}: no variant moved the selection that way{tries}; the plant is as it was ({change}){why}"


def _relative_change(result, metric):
    """|after - before| / |before| of one metric (0 when it is missing or not finite)."""
    before, after = getattr(result.before, metric, None), getattr(result.after, metric, None)
    if before is None or after is None:
        return 0.0
    change = abs(float(after) - float(before)) / max(abs(float(before)), 1e-12)
    return change if np.isfinite(change) else 0.0


def _short(value):
    value = float(value)
    if value != 0 and (abs(value) >= 1e5 or abs(value) < 1e-2):
        return f"{value:.3g}"
    return f"{value:.0f}" if abs(value) >= 100 else f"{value:.3g}"


def variant_skeleton(
    lsystem: LSystem, n: int | None, seed: int, params: dict[str, Any] | None, constants: Mapping[str, float] | None = None
) -> Skeleton:
    """Derive the whole plant with a parameter combination ``{"rule", "constants"}`` (a preview)."""
    consts = dict(lsystem.constants if constants is None else constants)
    return lsystem.derive(n=n, seed=seed, constants=consts, params=params or None).skeleton()
