"""The whole offline exploration of a grammar: sweep -> deltas -> PCA -> 27 picks, and its files.

:func:`explore` runs the pipeline and returns an :class:`Exploration`;
:func:`write_exploration` writes the directory other packages read:

``variants.csv``  one row per variant: ``id, rule``, each varied constant,
                  the ten metrics, the ten deltas (``d_<metric>``), ``pc1..pc3``
                  and ``failed`` (0/1).  ``id`` is the variant index.
``pca.json``      metrics, components (3x10), explained variance (and ratio),
                  mean, scale, standardized flag, base metrics, interest points,
                  the summed distance of each matching method, run facts.
``picks.json``    27 objects ``{"id", "variant", "pca", "params", "image"}``,
                  ids 1..27 with PC1 varying slowest (``image`` only with thumbnails).

>>> import tempfile
>>> exp = explore("grammars/honda_sympodial.lsys", n=3, n_jobs=1, cache=False)
>>> exp.picks.variant.shape, sorted(exp.matching)
((27,), ['greedy', 'optimal', 'sequential'])
>>> folder = tempfile.mkdtemp()
>>> sorted(p.name for p in write_exploration(exp, folder).values())
['pca.json', 'picks.json', 'variants.csv']
>>> info = read_exploration_info(folder)
>>> info.name, info.grammar_file.name, info.n, info.seed
('honda_sympodial', 'honda_sympodial.lsys', 3, 0)

An exploration folder may come from someone else: :func:`read_exploration_info`
reads its ``pca.json`` as a regular UTF-8 file of bounded size, refuses values
of the wrong type, and finds the grammar it names only among the shipped
grammars (or a grammars folder the caller gives) or inside the exploration
folder itself: ``"../outside/evil"`` or ``"/etc/x"`` is refused, never read.
"""

from __future__ import annotations

import csv
import json
import os
import pathlib
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ramure.errors import RamureError, ValueRefused
from ramure.io import inside, open_atomic, read_json, write_text

from .pca import DeltaPCA
from .picks import Picks, match_totals, pick_variants
from .plant import METRIC_NAMES
from .sweep import VariantSweep, as_lsystem

if TYPE_CHECKING:
    from ramure.lsys import LSystem


def grammar_name(grammar: LSystem | str | os.PathLike) -> str:
    """The name a grammar is stored under: its file stem (``honda_sympodial``), else ``grammar``."""
    if isinstance(grammar, (str, pathlib.Path)):
        return pathlib.Path(grammar).stem
    filename = getattr(getattr(grammar, "grammar", None), "filename", None)
    return pathlib.Path(filename).stem if filename else "grammar"


@dataclass
class Exploration:
    """A fitted ``sweep``, its ``pca``, the cloud ``points`` (N,3), the ``picks``,
    the summed distance per matching method and the total ``seconds``."""

    name: str
    sweep: VariantSweep
    pca: DeltaPCA
    points: np.ndarray
    picks: Picks
    matching: dict
    seconds: float

    def combinations(self) -> list:
        return [self.sweep.design_.combination(i) for i in range(self.sweep.n_variants_)]

    def pick_records(self, images: Sequence[str | os.PathLike | None] | None = None) -> list[dict]:
        """The ``picks.json`` list (``images``: 27 paths relative to the output directory)."""
        combos = {int(v): self.sweep.combination(int(v)) for v in self.picks.variant}
        return self.picks.records(combos, images)

    def summary(self, images: Sequence[str | os.PathLike | None] | None = None) -> dict:
        """A JSON-able summary: variant count, the picks, matching distances, seconds."""
        s = self.sweep
        return {
            "grammar": self.name,
            "n": s.n_,
            "seed": s.seed,
            "beta": s.design_.beta,
            "mode": s.design_.mode,
            "constants": list(s.names_),
            "rules": s.n_rules_,
            "variants": int(s.n_variants_),
            "failed": int(s.failed_.sum()),
            "from_cache": bool(s.from_cache_),
            "explained_variance_ratio": self.pca.explained_variance_ratio_.tolist(),
            "standardized": bool(self.pca.standardize),
            "matching": {"method": self.picks.method, **self.matching},
            "picks": [{"id": r["id"], "variant": r["variant"], "params": r["params"]} for r in self.pick_records(images)],
            "seconds": round(self.seconds, 4),
        }


def explore(
    grammar: LSystem | str | os.PathLike,
    standardize: bool = False,
    match: str = "optimal",
    progress: Callable[[int, int], None] | None = None,
    cancel: threading.Event | Callable[[], bool] | None = None,
    sweep: VariantSweep | None = None,
    **sweep_options: Any,
) -> Exploration:
    """Sweep ``grammar`` (LSystem or path), run the PCA and pick the 27 variants.

    ``sweep_options`` are :class:`VariantSweep`'s parameters (``n``, ``seed``, ``beta``,
    ``constants``, ``mode``, ``n_samples``, ``n_jobs``, ``cache``, ...): one keyword set, the
    sweep's own, so a new sweep option needs no change here; an unknown one is refused with
    :class:`~ramure.errors.ValueRefused`.  ``standardize`` goes to the PCA, ``match`` to the
    27 picks.  Pass an already configured (or fitted) :class:`VariantSweep` as ``sweep`` to
    keep a handle on it (e.g. to call ``sweep.cancel()`` from a GUI); sweep options are then
    refused rather than ignored.
    """
    t0 = time.perf_counter()
    ls = as_lsystem(grammar)
    if sweep is None:
        sweep = VariantSweep().set_params(**sweep_options)
    elif sweep_options:
        raise ValueRefused(f"give a sweep or sweep options ({', '.join(sorted(sweep_options))}), not both")
    if not hasattr(sweep, "deltas_"):
        sweep.fit(ls, progress=progress, cancel=cancel)
    pca = DeltaPCA(standardize=standardize).fit(sweep.deltas_)
    points = pca.transform(sweep.deltas_)
    picks = pick_variants(points, method=match)
    return Exploration(grammar_name(grammar), sweep, pca, points, picks, match_totals(points), time.perf_counter() - t0)


def _num(v):
    return "" if not np.isfinite(v) else repr(float(v))


def write_variants_csv(exp: Exploration, path: str | os.PathLike) -> None:
    s = exp.sweep
    header = ["id", "rule", *s.names_, *METRIC_NAMES, *(f"d_{m}" for m in METRIC_NAMES), "pc1", "pc2", "pc3", "failed"]
    with open_atomic(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(header)
        for i in range(s.n_variants_):
            w.writerow(
                [
                    i,
                    int(s.rules_[i]),
                    *map(_num, s.values_[i]),
                    *map(_num, s.metrics_[i]),
                    *map(_num, s.deltas_[i]),
                    *map(_num, exp.points[i]),
                    int(s.failed_[i]),
                ]
            )


def write_exploration(
    exp: Exploration, directory: str | os.PathLike, images: Sequence[str | os.PathLike | None] | None = None
) -> dict[str, pathlib.Path]:
    """Write ``variants.csv``, ``pca.json`` and ``picks.json`` to ``directory``; returns their paths.

    ``images`` are the 27 thumbnail paths relative to ``directory`` (or None).
    """
    out = pathlib.Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"variants": out / "variants.csv", "pca": out / "pca.json", "picks": out / "picks.json"}
    write_variants_csv(exp, paths["variants"])
    s = exp.sweep
    doc = {
        **exp.pca.to_dict(METRIC_NAMES),
        "grammar": exp.name,
        "n": s.n_,
        "seed": s.seed,
        "beta": s.design_.beta,
        "mode": s.design_.mode,
        "constants": list(s.names_),
        "base_constants": s.base_constants_,
        "rules": s.n_rules_,
        "variants": int(s.n_variants_),
        "base_metrics": dict(zip(METRIC_NAMES, s.base_metrics_.tolist())),
        "interest_points": exp.picks.targets.tolist(),
        "matching": {"method": exp.picks.method, **exp.matching},
    }
    write_text(paths["pca"], json.dumps(doc, indent=1))
    write_text(paths["picks"], json.dumps(exp.pick_records(images), indent=1))
    return paths


#: Largest ``pca.json`` read (bytes); one holds a few kilobytes.
MAX_PCA_JSON_BYTES = 4 << 20
#: Largest derivation step count ``pca.json`` may name (the derivation has its own limits too).
MAX_EXPLORATION_N = 1000


@dataclass(frozen=True)
class ExplorationInfo:
    """What an exploration folder's ``pca.json`` says: the grammar's ``name``, its file when it
    is found where files may be read (``grammar_file``, else None), ``n`` (None: unknown) and ``seed``."""

    name: str
    grammar_file: pathlib.Path | None
    n: int | None
    seed: int


def read_exploration_info(
    directory: str | os.PathLike, grammars_dir: str | os.PathLike | None = None, name: str | None = None
) -> ExplorationInfo:
    """Read and check ``directory/pca.json`` (see the module docstring); refused with one
    :class:`~ramure.errors.RamureError` line naming the file and the value.

    ``grammar`` must be text: a shipped grammar name (``"honda_sympodial"``, ``"amap/rauh"``),
    a name of a ``.lsys`` file in ``grammars_dir`` when given, or a ``.lsys`` file inside
    ``directory``; each resolved (links and ``..``) and checked to lie inside its folder.  A
    name found nowhere is kept as the display name with no file.  ``n`` is an integer 0 to
    :data:`MAX_EXPLORATION_N` or null, ``seed`` an integer or null.  Without ``pca.json``:
    ``name`` (default: the folder's name), no n, seed 0.
    """
    directory = pathlib.Path(directory)
    path = directory / "pca.json"
    doc = _read_json(path) if path.exists() else {}
    where = str(path)
    if not isinstance(doc, dict):
        raise RamureError(f"{where}: expected a JSON object, not {type(doc).__name__}")
    grammar = doc.get("grammar", name or directory.name)
    if not isinstance(grammar, str) or not grammar.strip() or len(grammar) > 255:
        raise RamureError(f"{where}: 'grammar' must be a grammar name (text), not {_shown(grammar)}")
    n, seed = doc.get("n"), doc.get("seed")
    if n is not None and not _is_int(n, 0, MAX_EXPLORATION_N):
        raise RamureError(f"{where}: 'n' must be an integer from 0 to {MAX_EXPLORATION_N}, not {_shown(n)}")
    if seed is not None and not _is_int(seed, -(2**63), 2**63 - 1):
        raise RamureError(f"{where}: 'seed' must be an integer, not {_shown(seed)}")
    return ExplorationInfo(grammar, find_grammar(grammar, grammars_dir, directory, where), n, int(seed or 0))


def _read_json(path: pathlib.Path) -> object:
    return read_json(path, MAX_PCA_JSON_BYTES, "exploration file")


def _is_int(value: object, low: int, high: int) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and low <= value <= high


def _shown(value: object) -> str:
    text = json.dumps(value) if not isinstance(value, str) else repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def find_grammar(
    grammar: str,
    grammars_dir: str | os.PathLike | None = None,
    directory: str | os.PathLike | None = None,
    where: str = "grammar",
) -> pathlib.Path | None:
    """The ``.lsys`` file grammar name ``grammar`` stands for, confined, or None if there is none.

    Looked up among the shipped grammars (or in ``grammars_dir`` when given), then inside
    ``directory``; a file is taken only if, links and ``..`` resolved, it lies in that folder.
    An absolute path, ``..`` or ``~`` is refused (:class:`~ramure.errors.RamureError`).

    >>> find_grammar("amap/rauh").name, find_grammar("no_such_grammar")
    ('rauh.lsys', None)
    """
    from ramure import grammars

    relative = pathlib.PurePosixPath(grammar.replace("\\", "/"))
    if relative.is_absolute() or ".." in relative.parts or grammar.startswith("~"):
        raise RamureError(
            f"{where}: grammar {grammar!r} is not a grammar name; it must name a shipped grammar "
            "or a file inside the exploration folder"
        )
    stem = str(relative)[: -len(".lsys")] if relative.suffix == ".lsys" else str(relative)
    folders = [pathlib.Path(grammars_dir) if grammars_dir else grammars.FOLDER]
    if directory is not None:
        folders.append(pathlib.Path(directory))
    for folder in folders:
        candidate = folder / f"{stem}.lsys"
        if candidate.is_file() and inside(candidate, folder):
            return candidate.resolve()
    return None
