"""A study's pictures, rendered once when the study is made: one renderer, files in the study folder.

Every front end (desktop, notebook, web) shows these files, so every participant sees the same
pictures.  With the ``shared`` framing (the default) the 27 plants of a set are rendered with one
camera framed on the union of their bounds, and the same scale bar stands beside each plant, so
that a tall plant looks tall; ``own`` frames each plant on its own bounds (size is then
invisible).  What was done is recorded in the study's settings (``stimuli``): the framing, the
picture size, and per set the bounds, the bar's length in the grammar's units and the folder.
"""

from __future__ import annotations

import math
import os
import re
from typing import TYPE_CHECKING

import numpy as np

from ramure.errors import RamureError

if TYPE_CHECKING:
    from ramure.lsys import LSystem
    from ramure.studies import Study

STIMULI_DIR = "stimuli"


def study_grammar(
    study: Study, grammar: str, grammars_dir: str | os.PathLike | None = None, confined: bool = True
) -> tuple[LSystem | None, int | None, int]:
    """The LSystem, n and seed to derive a study grammar's picks with (None if not found).

    The exploration folder's ``pca.json`` is read by
    :func:`ramure.metrics.exploration.read_exploration_info`: the grammar it names is read
    only from the grammars folder or from inside the exploration folder.  With ``confined`` (a
    participant's window) that folder, named by the database, is read only if it lies inside
    the study's own folder, as its pictures do; otherwise the grammar is looked up by its name.
    A refused ``pca.json`` derives nothing.
    """
    from ramure.io import inside
    from ramure.lsys import LSystem
    from ramure.metrics.exploration import ExplorationInfo, find_grammar, read_exploration_info

    try:
        recorded = study.grammar_source(grammar)
        if recorded and (not confined or inside(recorded, study.path.parent)):
            info = read_exploration_info(recorded, grammars_dir, name=grammar)
        else:
            info = ExplorationInfo(grammar, find_grammar(grammar, grammars_dir), None, 0)
        if info.grammar_file is None:
            return None, None, 0
        lsystem = LSystem.from_file(info.grammar_file)
    except RamureError:
        return None, None, 0
    return lsystem, info.n if info.n is not None else lsystem.n, info.seed


def bar_length(height: float) -> float:
    """A round scale-bar length (1, 2 or 5 times a power of ten) near a quarter of ``height``.

    >>> bar_length(10.0), bar_length(3.1), bar_length(0.0)
    (2.0, 0.5, 1.0)
    """
    if not height > 0:
        return 1.0
    target = height / 4
    power = 10 ** math.floor(math.log10(target))
    return float(max((m * power for m in (1, 2, 5) if m * power <= target), default=power))


def shared_bounds(bounds: np.ndarray) -> np.ndarray:
    """The union of per-plant bounds ``(k, 6)`` (xmin, xmax, ymin, ymax, zmin, zmax), widened on
    the left for the scale bar.

    >>> shared_bounds(np.array([[0, 1, 0, 1, 0, 4], [-1, 2, 0, 1, 0, 8.0]])).tolist()
    [-1.75, 2.0, 0.0, 1.0, 0.0, 8.0]
    """
    b = np.asarray(bounds, float)
    union = np.array([b[:, 0].min(), b[:, 1].max(), b[:, 2].min(), b[:, 3].max(), b[:, 4].min(), b[:, 5].max()])
    union[0] -= 0.25 * (union[1] - union[0])  # room for the bar
    return union


def _folder_name(index: int, grammar: str) -> str:
    return f"{index:02d}-{re.sub(r'[^A-Za-z0-9_-]+', '_', grammar)[:40]}"


def render_stimuli(
    study: Study,
    size: int = 480,
    grammars_dir: str | os.PathLike | None = None,
) -> dict[str, str]:
    """Render the 27 picks of each grammar of ``study`` into ``STUDY_FOLDER/stimuli/NN-NAME/``, store
    them as the picks' pictures, and record the framing in the settings (``stimuli``).

    The framing is the study config's (``shared`` or ``own``).  A grammar whose file is not
    found keeps the pictures it came with.  Returns what was done per grammar: ``rendered``
    or why not.
    """
    from ramure.app.thumbnails import render_framed

    framing = study.config().framing
    record: dict = {"framing": framing, "size": [size, size], "grammars": {}}
    done: dict[str, str] = {}
    for index, grammar in enumerate(study.grammars, start=1):
        lsystem, n, seed = study_grammar(study, grammar, grammars_dir, confined=False)
        if lsystem is None:
            done[grammar] = "not rendered: no grammar file found (the exploration's own pictures are kept)"
            record["grammars"][grammar] = {"rendered": False}
            continue
        picks = study.picks(grammar)
        consts = dict(lsystem.constants)
        skeletons = [lsystem.derive(n=n, seed=seed, constants=consts, params=p.params or None).skeleton() for p in picks]
        folder = study.path.parent / STIMULI_DIR / _folder_name(index, grammar)
        folder.mkdir(parents=True, exist_ok=True)
        paths = [folder / f"pick_{p.id:02d}.png" for p in picks]
        bounds = np.array([_bounds(sk) for sk in skeletons])
        info: dict = {"rendered": True, "folder": folder.relative_to(study.path.parent).as_posix()}
        if framing == "shared":
            frame = shared_bounds(bounds)
            bar = bar_length(float(frame[5] - frame[4]))
            info.update(bounds=[round(float(v), 6) for v in frame], bar=bar)
            render_framed(skeletons, paths, (size, size), frame.tolist(), bar)
        else:
            render_framed(skeletons, paths, (size, size), None, None)
        study.set_pictures(grammar, {p.id: path for p, path in zip(picks, paths)})
        record["grammars"][grammar] = info
        done[grammar] = "rendered"
    study.set_setting("stimuli", record)
    return done


def _bounds(skeleton) -> list[float]:
    if not len(skeleton):
        return [0.0, 1.0, 0.0, 1.0, 0.0, 1.0]
    points = np.concatenate([skeleton.start, skeleton.end])
    low, high = points.min(axis=0), points.max(axis=0)
    return [float(low[0]), float(high[0]), float(low[1]), float(high[1]), float(low[2]), float(high[2])]
