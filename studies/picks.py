"""The 27 picked variants of a grammar: read from an exploration, or synthesised.

The metrics/exploration step writes, per grammar, a directory holding
``picks.json``: a list of 27 objects ``{"id": 1..27, "variant": int,
"pca": [x, y, z], "params": {"rule": int, "constants": {...}}, "image":
"thumbs/pick_01.png"}`` (``image`` relative to that directory, optional).

>>> picks = lattice_picks(seed=0)
>>> len(picks), picks[0].id, picks[26].id
(27, 1, 27)
>>> picks[0].pca[0] < picks[13].pca[0] < picks[26].pca[0]   # PC1 varies slowest
True
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from numpy.typing import ArrayLike

import json
import math
import numbers
import pathlib
from dataclasses import dataclass, field

import numpy as np

from ramure.errors import RamureError
from ramure.io import read_json
from ramure.studies.errors import StudyInputError

N_PICKS = 27
PICK_IDS = tuple(range(1, N_PICKS + 1))
#: Largest ``picks.json`` read (bytes); 27 picks take a few kilobytes.
MAX_PICKS_JSON_BYTES = 4 << 20


@dataclass(frozen=True)
class Pick:
    """One of the 27 images of a grammar: ``id`` 1-27 and its variant."""

    id: int
    variant: int
    pca: tuple
    params: dict = field(hash=False)
    image: str | None = None


def _fail(where, message):
    raise StudyInputError(f"{where}: {message}")


def _check_pick(obj, where):
    if not isinstance(obj, dict):
        _fail(where, f"expected an object, got {type(obj).__name__}")
    for key in ("id", "variant", "pca", "params"):
        if key not in obj:
            _fail(where, f"missing key {key!r}")
    pid, variant, pca, params = obj["id"], obj["variant"], obj["pca"], obj["params"]
    if isinstance(pid, bool) or not isinstance(pid, numbers.Integral) or not 1 <= int(pid) <= N_PICKS:
        _fail(where, f"id {pid!r} is not an integer 1-27")
    if isinstance(variant, bool) or not isinstance(variant, numbers.Integral) or variant < 0:
        _fail(where, f"variant {variant!r} is not a non-negative integer")
    if (
        not isinstance(pca, (list, tuple))
        or len(pca) != 3
        or not all(isinstance(v, numbers.Real) and math.isfinite(v) for v in pca)
    ):
        _fail(where, f"pca {pca!r} is not three finite numbers")
    if not isinstance(params, dict) or "rule" not in params:
        _fail(where, "params must be an object with a 'rule'")
    image = obj.get("image")
    if image is not None and not isinstance(image, str):
        _fail(where, f"image {image!r} is not a path")
    return Pick(int(pid), int(variant), tuple(float(v) for v in pca), dict(params), image)


def picks_from_data(items: Sequence[dict | Pick], where: str = "picks") -> list[Pick]:
    """Validate plain data (a list of 27 dicts or :class:`Pick`) into picks sorted by id."""
    if not isinstance(items, (list, tuple)):
        _fail(where, "expected a list of 27 picks")
    picks = [p if isinstance(p, Pick) else _check_pick(p, f"{where}[{i}]") for i, p in enumerate(items)]
    ids = sorted(p.id for p in picks)
    if ids != list(PICK_IDS):
        missing = sorted(set(PICK_IDS) - set(ids))
        doubled = sorted({i for i in ids if ids.count(i) > 1})
        detail = []
        if missing:
            detail.append(f"missing ids {missing}")
        if doubled:
            detail.append(f"repeated ids {doubled}")
        _fail(where, f"expected the 27 ids 1-27 once each ({'; '.join(detail)})")
    return sorted(picks, key=lambda p: p.id)


def load_picks(directory: str | os.PathLike) -> list[Pick]:
    """Read ``directory/picks.json`` (a regular UTF-8 file of at most :data:`MAX_PICKS_JSON_BYTES`);
    image paths become absolute, and must lie inside ``directory``."""
    directory = pathlib.Path(directory)
    path = directory / "picks.json"
    if not path.exists():
        raise StudyInputError(f"{directory}: no picks.json (run the exploration first)")
    try:
        items = read_json(path, MAX_PICKS_JSON_BYTES, "picks file")  # no pipe, no device, bounded
    except RamureError as exc:
        raise StudyInputError(str(exc)) from None
    if not isinstance(items, list):
        raise StudyInputError(f"{path}: expected a list of 27 picks")
    picks = picks_from_data(items, where=str(path))
    return [Pick(p.id, p.variant, p.pca, p.params, inside_folder(directory, p.image, str(path))) for p in picks]


def inside_folder(folder: str | os.PathLike, image: str | os.PathLike | None, where: str) -> str | None:
    """``image`` resolved against ``folder``; refused unless it lies inside ``folder``.

    Symbolic links and ``..`` are resolved first, so a picks file (or a study
    database) can never make Ramure read ``/etc/...`` or another user's files.
    """
    if not image:
        return None
    root = pathlib.Path(folder).resolve()
    path = (root / str(image)).resolve()
    if not path.is_relative_to(root):
        raise StudyInputError(f"{where}: picture {image!r} lies outside {root}; pictures must be inside the study's own folder")
    return str(path)


def lattice_index(levels: ArrayLike) -> np.ndarray:
    """Pick id (1-27) of lattice levels ``(i, j, k)`` in {0, 1, 2}, PC1 slowest.

    >>> lattice_index([[0, 0, 0], [0, 0, 1], [1, 0, 0], [2, 2, 2]]).tolist()
    [1, 2, 10, 27]
    """
    levels = np.asarray(levels)
    return 1 + 9 * levels[..., 0] + 3 * levels[..., 1] + levels[..., 2]


def lattice_picks(seed: int = 0, extent: tuple[float, float, float] = (60.0, 30.0, 12.0), noise: float = 0.05) -> list[Pick]:
    """27 synthetic picks on the 3x3x3 lattice of a box, with seeded noise.

    ``extent`` is the half-size of the box along PC1..PC3; each point moves by
    Gaussian noise of ``noise * extent``.  The constants follow the lattice
    level (-10 %, 0, +10 %), one constant per axis, all on rule 1.
    """
    rng = np.random.default_rng(seed)
    scale = np.asarray(extent, dtype=float)
    grid = np.stack(np.meshgrid(*[np.arange(3)] * 3, indexing="ij"), -1).reshape(-1, 3)
    points = (grid - 1) * scale + rng.normal(0.0, noise, size=(N_PICKS, 3)) * scale
    base = {"r1": 0.9, "a0": 45.0, "wr": 0.707}
    picks = []
    for levels, point in zip(grid, points):
        pid = int(lattice_index(levels))
        constants = {name: round(value * (1 + 0.1 * (lvl - 1)), 6) for (name, value), lvl in zip(base.items(), levels)}
        picks.append(
            Pick(
                pid,
                int(pid * 17 + int(rng.integers(0, 17))),
                tuple(float(v) for v in point),
                {"rule": 1, "constants": constants},
                None,
            )
        )
    return sorted(picks, key=lambda p: p.id)


def synthetic_grammars(count: int = 3, seed: int = 0) -> dict:
    """``count`` fake grammars ``synth1..`` with lattice picks of varied box sizes."""
    rng = np.random.default_rng(seed)
    grammars = {}
    for n in range(count):
        extent = np.sort(rng.uniform(8.0, 80.0, size=3))[::-1]
        grammars[f"synth{n + 1}"] = lattice_picks(seed=seed * 1000 + n, extent=tuple(extent))
    return grammars


#: Two picks are near-duplicates when their PCA points (their metrics) lie closer than this
#: fraction of the diagonal of the box holding the 27 points: 0.2 %, so that picks whose metrics
#: agree but for rounding, or a constant that changes nothing, are caught, while two honda
#: variants 6 degrees apart in one angle (0.6 % of their cloud) are still told apart.
NEAR_DUPLICATE_TOLERANCE = 0.002


def _ranges(ids: Sequence[int]) -> str:
    """``[1, 2, 3, 5]`` -> ``"1-3, 5"``."""
    runs: list[list[int]] = []
    for i in sorted(ids):
        if runs and i == runs[-1][-1] + 1:
            runs[-1].append(i)
        else:
            runs.append([i])
    return ", ".join(f"{r[0]}-{r[-1]}" if len(r) > 1 else str(r[0]) for r in runs)


def coinciding_picks(picks: Sequence[Pick], tolerance: float = NEAR_DUPLICATE_TOLERANCE) -> list[list[int]]:
    """The sets of pick ids that show the same plant, largest first (each of two or more picks).

    Two picks coincide when they are the same variant, have the same parameters
    (rule and constants), or their PCA points are closer than ``tolerance`` times
    the diagonal of the box holding all the points; coinciding is made transitive.

    >>> picks = lattice_picks(seed=0)
    >>> coinciding_picks(picks)
    []
    >>> same = [Pick(p.id, 7, (0.0, 0.0, 0.0), {"rule": 1}) for p in picks]
    >>> [len(s) for s in coinciding_picks(same)]
    [27]
    """
    points = np.array([p.pca for p in picks], dtype=float)
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) if len(picks) else 0.0
    near = np.linalg.norm(points[:, None] - points[None, :], axis=-1) <= tolerance * diagonal
    keys = [json.dumps(p.params, sort_keys=True) for p in picks]
    variants = np.array([p.variant for p in picks])
    same = near | (variants[:, None] == variants[None, :]) | (np.array(keys)[:, None] == np.array(keys)[None, :])
    label = np.arange(len(picks))
    for _ in range(len(picks)):  # propagate the smallest index along the links (27 picks: at most 27 rounds)
        spread = np.where(same, label[None, :], len(picks)).min(axis=1)
        if (spread == label).all():
            break
        label = spread
    sets = [sorted(picks[int(i)].id for i in np.flatnonzero(label == root)) for root in np.unique(label)]
    return sorted((s for s in sets if len(s) > 1), key=lambda s: (-len(s), s[0]))


def check_distinct(picks: Sequence[Pick], where: str) -> None:
    """Refuse, in one line, picks that do not show 27 different plants (see :func:`coinciding_picks`),
    naming the picks that coincide and what to do instead."""
    sets = coinciding_picks(picks)
    if not sets:
        return
    distinct = len(picks) - sum(len(s) - 1 for s in sets)
    shown = " | ".join(_ranges(s) for s in sets[:6]) + (" | ..." if len(sets) > 6 else "")
    raise StudyInputError(
        f"{where}: only {distinct} different plants among the {len(picks)} picks; these picks coincide: {shown} "
        f"(same variant, same parameters, or PCA points within {NEAR_DUPLICATE_TOLERANCE:.1%} of the cloud's size); "
        "explore again with another --seed, a wider --beta, more steps (-n) or other --constants, or use another grammar"
    )
