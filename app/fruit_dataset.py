"""A labelled dataset of defective fruit: ``ramure fruit batch`` (issue 17).

The thesis's stated use of its defect rules is a database of varied, defective fruit to
train a sorting system.  :func:`make_dataset` writes, for fruit ``i`` of ``count``:

* ``fruit_0000.png`` (the whole fruit) and ``fruit_0000_cut.png`` (cut through its axis,
  tissues showing), pictures of ``picture`` pixels;
* ``fruit_0000.vtu``: the cells with their ``tissue`` (and ``label``, ``volume``) data;
* ``fruit_0000.json``: the labels: malformation (recipe and measured flatness,
  lopsidedness, ribbing), every defect's facts, volume lost, the OECD/UNECE grade with
  its reasons, and the files.

and ``dataset.json``, the manifest: the settings, ``"complete"``, one summary row per fruit
and the marketable count.

**Nothing half-done.**  The manifest is written first, ``"complete": false``, and rewritten
``true`` last; a fruit's labels are its last file, so a fruit with labels is whole.  A folder
that is not empty is refused unless told: ``resume=True`` (``--resume``) finishes the dataset
there (same settings, only the fruit without labels are made), ``overwrite=True``
(``--overwrite``) removes the dataset files there first (``fruit_NNNN*`` and the manifest;
nothing else).  Labels and manifest hold no timings, so one seed gives byte-identical files.
Workers end when the process that started them dies (``kill -9`` included), instead of
writing on into a folder the user has seen the command give up on.

**Deterministic and independent.**  Fruit ``i`` draws all its random numbers from
``numpy.random.SeedSequence([seed, i])``: the same seed gives the same dataset, fruit
``i`` is the same whatever ``count`` and whichever worker builds it.

**Random defects** (``defects="random"``), per fruit: a malformation with probability
0.35 (a named shape or Grammar 3.1 at a rate up to 0.4), then each of crack (0.35), hail
(0.3), rot (0.2) and shrink (0.3) with parameters drawn in the ranges of
:data:`RANDOM_RANGES`; about a fifth of the fruit come out clean.  Hail stops at the
endocarp when the fruit has one (two volume subdivisions), else at the mesocarp.
``defects="none"``: clean fruit (still varied by their seeds).

**Speed.**  A process pool (``workers``, default 2) builds, damages, renders and writes
the fruit; each worker keeps one off-screen plotter for all its pictures.  Fruit are
built with one volume subdivision by default (``levels=1``: exocarp, mesocarp and the
columella; 2 adds endocarp, locules and seeds, at about 40 times the cost).
"""

from __future__ import annotations

import contextlib
import json
import os
import pathlib
import re
import sys
import time
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

import ramure.io as atomic
from ramure.errors import RamureError, ValueRefused

if TYPE_CHECKING:
    from ramure.gmap.kernel.map3 import GMap3

PICTURE = (256, 256)
#: Ranges the random defects are drawn from (mm on a fruit ``size_mm`` across).
RANDOM_RANGES: dict[str, tuple[Any, Any]] = {  # int ranges (counts, rings) and float ones
    "crack_width_mm": (0.5, 3.0),
    "crack_rings": (2, 5),
    "hail_count": (1, 6),
    "hail_depth_mm": (1.0, 5.0),
    "shrink_rate": (0.02, 0.10),
    "rot_rate": (0.02, 0.06),
    "malform_rate": (0.05, 0.4),
}
_STATE: dict[str, Any] = {}


def fruit_rng(seed: int, index: int) -> np.random.Generator:
    """The random generator of fruit ``index`` in a dataset of ``seed``."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), int(index)]))


def random_recipe(rng: np.random.Generator, preset: str = "round_tomato", levels: int = 1) -> dict:
    """Malformation and defect specs for one fruit (see the module docstring)."""
    from ramure.gmap.organs.malform import SHAPES

    r = RANDOM_RANGES
    malform = None
    if rng.random() < 0.35:
        if rng.random() < 0.5:
            malform = {"shape": str(rng.choice(sorted(SHAPES))), "rate": 0.0}
        else:
            malform = {"shape": None, "rate": round(float(rng.uniform(*r["malform_rate"])), 3)}
    specs = []
    crack = None
    if rng.random() < 0.35:
        first = int(rng.integers(1, 5))
        span = int(rng.integers(*r["crack_rings"]))
        crack = (
            "crack",
            {
                "kind": str(rng.choice(["longitudinal", "longitudinal", "transverse"])),
                "sector": int(rng.integers(0, 1000)),
                "rings": (first, first + span),
                "depth": 1,
                "width_mm": round(float(rng.uniform(*r["crack_width_mm"])), 2),
                "healed": int(rng.integers(0, 2)),
            },
        )
    if rng.random() < 0.3:
        lo = float(rng.uniform(r["hail_depth_mm"][0], r["hail_depth_mm"][1] - 1.0))
        specs.append(
            (
                "hail",
                {
                    "count": int(rng.integers(*r["hail_count"])),
                    "depth_mm": (round(lo, 2), round(lo + 1, 2)),
                    "stop": "endocarp" if levels >= 2 else "mesocarp",
                },
            )
        )
    if rng.random() < 0.2:
        specs.append(("rot", {"rate": round(float(rng.uniform(*r["rot_rate"])), 3)}))
    if rng.random() < 0.3:
        specs.append(("shrink", {"rate": round(float(rng.uniform(*r["shrink_rate"])), 3), "steps": int(rng.integers(1, 3))}))
    if crack is not None:  # last: the only defect that changes the topology (one index per fruit)
        specs.append(crack)
    return {"preset": preset, "malform": malform, "defects": specs, "seed": int(rng.integers(0, 2**31 - 1))}


def build_one(recipe: dict, levels: int = 1, size_mm: float = 65.0) -> tuple[GMap3, dict]:
    """Build and damage one fruit from its recipe: ``(map, labels)``."""
    from ramure.gmap.organs.defect_specs import apply_defects
    from ramure.gmap.organs.fruit import build_fruit
    from ramure.gmap.organs.malform import malform_params, shape_facts

    params = {}
    malform = recipe.get("malform")
    if malform:
        params = malform_params(recipe["preset"], seed=recipe["seed"], **malform)
    gm = build_fruit(recipe["preset"], seed=recipe["seed"], volume_levels=levels, **params)
    specs = [(kind, _fit(gm, kind, dict(opts))) for kind, opts in recipe["defects"]]
    labels = {
        "preset": recipe["preset"],
        "seed": recipe["seed"],
        "params": params,
        "malformation": None if not malform else {**malform, **shape_facts(gm)},
    }
    gm, facts = apply_defects(gm, specs, size_mm=size_mm, seed=recipe["seed"])
    labels.update(
        defects=facts["defects"],
        volume_lost_fraction=facts["volume_lost_fraction"],
        grade=facts["grade"],
        darts=gm.n_darts,
        volumes=gm.n_volumes,
    )
    return gm, labels


def _fit(gm, kind, opts):
    """Fit drawn crack positions to this fruit (sector modulo its sectors, rings inside)."""
    if kind == "crack":
        vd = gm.volume_data
        ph, rings = int(vd["sector"].max()) + 1, int(vd["ring"].max()) + 1
        opts["sector"] %= ph
        first, last = opts["rings"]
        last = min(last, rings - 2)
        opts["rings"] = (min(first, last), last)
    return opts


def _plotter(size):
    plotter = _STATE.get("plotter")
    if plotter is None:
        from ramure.app.render import headless_setup

        headless_setup()
        import pyvista as pv

        plotter = pv.Plotter(off_screen=True, window_size=list(size))
        plotter.set_background("white")  # type: ignore[arg-type]  # pyvista stubs: decorated method
        _STATE["plotter"] = plotter
    return plotter


def close_plotter() -> None:
    """Close this process's picture plotter (workers' plotters end with their process)."""
    plotter = _STATE.pop("plotter", None)
    if plotter is not None:
        plotter.close()


def _picture(surface, path, size, look) -> None:
    """One picture of a surface coloured by ``rgb`` cell data, looking along ``look``."""
    plotter = _plotter(size)
    plotter.clear_actors()
    plotter.add_mesh(surface, scalars="rgb", rgb=True, show_edges=False, render=False)
    b = np.asarray(surface.bounds, float).reshape(3, 2)
    centre, extent = b.mean(axis=1), float(np.max(b[:, 1] - b[:, 0])) or 1.0
    d = np.asarray(look, float) / np.linalg.norm(look)
    up = (0.0, 0.0, 1.0) if abs(d[2]) < 0.9 else (0.0, 1.0, 0.0)
    camera = plotter.camera
    camera.position, camera.focal_point, camera.up = tuple(centre + d * extent * 2.5), tuple(centre), up
    plotter.reset_camera(render=False, bounds=tuple(b.ravel()))
    atomic.write_with(path, lambda tmp: plotter.screenshot(str(tmp)))


def write_one(
    index: int,
    recipe: dict,
    folder: str | os.PathLike,
    levels: int = 1,
    size_mm: float = 65.0,
    picture: tuple[int, int] = PICTURE,
) -> dict:
    """Build, damage, picture and write fruit ``index``; returns its summary row."""
    from ramure.gmap.organs.tissue import tissue_rgb
    from ramure.gmap.kernel.cut import plane_cut
    from ramure.gmap.kernel.pyvista import to_unstructured_grid

    gm, labels = build_one(recipe, levels, size_mm)
    folder = pathlib.Path(folder)
    stem = f"fruit_{index:04d}"
    grid = to_unstructured_grid(gm)
    grid.cell_data["rgb"] = tissue_rgb(grid.cell_data["tissue"])
    skin = grid.extract_surface(algorithm="dataset_surface")
    _picture(skin, folder / f"{stem}.png", picture, (0.55, -0.75, 0.55))
    cut = plane_cut(grid, normal="y", mode="clip").extract_surface(algorithm="dataset_surface")
    _picture(cut, folder / f"{stem}_cut.png", picture, (0.35, 1.0, 0.25))  # facing the cut
    del grid.cell_data["rgb"]
    atomic.save_mesh(grid, folder / f"{stem}.vtu")
    files = {"picture": f"{stem}.png", "cut_picture": f"{stem}_cut.png", "grid": f"{stem}.vtu", "labels": f"{stem}.json"}
    record = {"index": index, **labels, "files": files}
    atomic.write_text(folder / f"{stem}.json", json.dumps(_plain(record), indent=1))  # last: the fruit is whole
    return summary_row(record)


def summary_row(record: Mapping[str, Any]) -> dict:
    """The manifest's row for a fruit, from its labels."""
    malformation = record["malformation"]
    return {
        "index": int(record["index"]),
        "grade": record["grade"]["grade"],
        "defects": [d["kind"] for d in record["defects"]],
        "malformation": None if not malformation else (malformation["shape"] or f"rate={malformation['rate']}"),
        "labels": record["files"]["labels"],
    }


def _plain(value):
    """JSON-ready copy: numpy scalars and tuples become Python numbers and lists."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _job(args):
    _end_if_orphaned()
    index, recipe, folder, levels, size_mm, picture = args
    return write_one(index, recipe, folder, levels, size_mm, picture)


_PARENT: list[int] = []  # in a worker: the pid of the process that started it


def _worker_start(parent: int) -> None:
    """Worker initializer: end this worker when ``parent`` dies (Linux: the kernel sends SIGTERM
    at once, even to a worker blocked on the dead queue; elsewhere each job checks first)."""
    _PARENT[:] = [parent]
    if sys.platform.startswith("linux"):
        import ctypes
        import signal

        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGTERM))  # PR_SET_PDEATHSIG
    _end_if_orphaned()


def _end_if_orphaned() -> None:
    if _PARENT and os.getppid() != _PARENT[0]:
        import signal

        os.kill(os.getpid(), signal.SIGTERM)  # the command died: write nothing more into its folder


def make_dataset(
    folder: str | os.PathLike,
    count: int = 100,
    seed: int = 0,
    defects: str = "random",
    preset: str = "round_tomato",
    levels: int = 1,
    size_mm: float = 65.0,
    workers: int = 2,
    picture: tuple[int, int] = PICTURE,
    resume: bool = False,
    overwrite: bool = False,
) -> dict:
    """Write ``count`` labelled fruit into ``folder`` (see the module docstring); the summary
    (the manifest, plus ``"seconds"``).

    Refused before anything is written: count outside 1..100000, an unknown
    ``defects`` mode or preset, levels outside 1..2, workers < 1, a folder that is not empty
    without ``resume`` or ``overwrite``, a ``resume`` with other settings than the folder's.
    """
    from ramure.gmap.organs.fruit import PRESETS

    if int(count) != count or not 1 <= count <= 100_000:
        raise ValueRefused(f"--count must be a whole number in 1..100000, got {count}")
    if defects not in ("random", "none"):
        raise ValueRefused(f"--defects must be 'random' or 'none', got {defects!r}")
    if preset not in PRESETS:
        raise ValueRefused(f"unknown fruit preset {preset!r}; choose one of {', '.join(PRESETS)}")
    if levels not in (1, 2):
        raise ValueRefused(f"--levels must be 1 or 2 (volume subdivisions; tissues need at least 1), got {levels}")
    if int(workers) != workers or workers < 1:
        raise ValueRefused(f"--workers must be >= 1, got {workers}")
    if not (np.isfinite(size_mm) and size_mm > 0):
        raise ValueRefused(f"--size-mm must be a finite number > 0, got {size_mm}")
    if resume and overwrite:
        raise ValueRefused("--resume and --overwrite exclude each other")
    folder = pathlib.Path(folder)
    if folder.exists() and not folder.is_dir():
        raise ValueRefused(f"-o {folder}: exists and is not a folder")
    settings = {
        "count": int(count),
        "seed": int(seed),
        "defects": defects,
        "preset": preset,
        "levels": levels,
        "size_mm": float(size_mm),
        "picture": [int(v) for v in picture],
    }
    _prepare(folder, settings, resume, overwrite)
    t0 = time.perf_counter()
    write_manifest(folder, settings, [], complete=False)
    done = {i for i in range(int(count)) if resume and (folder / f"fruit_{i:04d}.json").is_file()}
    jobs = []
    for i in range(int(count)):
        if i in done:
            continue
        recipe = random_recipe(fruit_rng(seed, i), preset, levels)
        if defects == "none":
            recipe.update(malform=None, defects=[])
        jobs.append((i, recipe, str(folder), levels, float(size_mm), tuple(picture)))
    rows = (_run(jobs, int(workers)) if jobs else []) + [_row_of(folder, i) for i in sorted(done)]
    summary = write_manifest(folder, settings, sorted(rows, key=lambda r: r["index"]), complete=True)
    return {**summary, "seconds": round(time.perf_counter() - t0, 3)}


MANIFEST = "dataset.json"
_OURS = re.compile(r"fruit_\d{4,}(_cut)?\.(png|vtu|json)|" + re.escape(MANIFEST))


def write_manifest(folder: pathlib.Path, settings: Mapping[str, Any], rows: Sequence[dict], complete: bool) -> dict:
    """Write ``dataset.json`` (atomically) and return what it holds."""
    summary = {
        "format": "ramure-fruit-dataset",
        **settings,
        "complete": complete,
        "marketable": sum(r["grade"] == "marketable" for r in rows),
        "fruit": list(rows),
    }
    atomic.write_text(folder / MANIFEST, json.dumps(_plain(summary), indent=1))
    return summary


def _prepare(folder: pathlib.Path, settings: Mapping[str, Any], resume: bool, overwrite: bool) -> None:
    """Make ``folder`` ready: created, or checked for ``resume``, or cleared of ours for ``overwrite``."""
    entries = sorted(folder.iterdir()) if folder.is_dir() else []
    if resume:
        old = _read_manifest(folder)
        if old is None:
            raise ValueRefused(f"--resume: {folder} holds no dataset to finish (no readable {MANIFEST})")
        differ = [k for k in settings if old.get(k) != settings[k]]
        if differ:
            raise ValueRefused(
                f"--resume: the dataset in {folder} was made with other settings ({', '.join(differ)}); "
                "give the same ones, or --overwrite"
            )
        return
    if entries and not overwrite:
        raise ValueRefused(f"-o {folder} is not empty: --resume finishes the dataset there, --overwrite replaces it")
    for entry in entries:
        if entry.is_file() and _OURS.fullmatch(entry.name):
            entry.unlink()
    folder.mkdir(parents=True, exist_ok=True)


def _read_manifest(folder: pathlib.Path) -> dict | None:
    try:
        data = json.loads(atomic.read_regular(folder / MANIFEST, 64 * 2**20, MANIFEST))
    except (RamureError, ValueError):
        return None
    return data if isinstance(data, dict) and data.get("format") == "ramure-fruit-dataset" else None


def _row_of(folder: pathlib.Path, index: int) -> dict:
    """The manifest row of fruit ``index`` made before a resume, from its labels."""
    path = folder / f"fruit_{index:04d}.json"
    try:
        return summary_row(json.loads(atomic.read_regular(path, 64 * 2**20, "fruit labels")))
    except (ValueError, KeyError, TypeError) as exc:
        raise RamureError(f"--resume: {path} is not a fruit's labels ({type(exc).__name__}); --overwrite remakes them") from None


def _warm() -> None:
    """Import and load in this process what every fruit needs (forked workers inherit it):
    pyvista and VTK's rendering modules, the compiled defect loops, a tiny fruit's path."""
    from ramure.app.render import headless_setup

    headless_setup()
    import pyvista  # noqa: F401
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
    from ramure.gmap.organs.defect_specs import apply_defects
    from ramure.gmap.organs.fruit import build_fruit

    gm = build_fruit("round_tomato", precision=4, ph=4, nbvolangle=2, volume_levels=1, seeds=0)
    apply_defects(gm, [("shrink", {"rate": 0.01})])


def _run(jobs, workers):
    if workers == 1 or len(jobs) == 1:
        try:
            return [_job(j) for j in jobs]
        finally:
            close_plotter()  # this process's GL context must not outlive the dataset
    _warm()
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    ctx = mp.get_context("fork" if hasattr(os, "fork") else "spawn")
    chunk = max(1, len(jobs) // (4 * workers))
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_worker_start, initargs=(os.getpid(),)) as pool:
        return list(pool.map(_job, jobs, chunksize=chunk))
