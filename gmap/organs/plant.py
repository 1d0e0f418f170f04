"""Volumetric fruit in a derived plant: one fruit per ``Fruit`` organ.

Each fruit is built at its organ's turtle frame, with the stem end at the
organ's position and the body hanging along the turtle heading H (the fruit's
axis, blossom end to stem end, is ``-H``; its L is the turtle's L).  ``size``
is the largest extent of the fruit's own bounding box, measured along its
frame (the diameter of a round tomato, the length of a banana).  Every
volume carries the organ's history-leaf id in the ``leaf_id`` attribute, so a
picked cell leads back to the derivation, and each fruit draws its random
numbers from ``seed + leaf_id``: regenerating one fruit (new seed, preset,
size or parameters, through ``overrides``) leaves the others untouched.

Fruit with the same preset and parameters (and, when tissues are built, the
same seed) are built once and copied into place.

>>> import numpy as np
>>> frames = np.repeat(np.eye(3)[None], 2, axis=0)          # rows H, L, U
>>> gm = fruits_from_organs([[0, 0, 0], [5, 0, 0]], frames, [1.0, 2.0], [11, 42])
>>> gm.n_volumes, sorted(set(gm.volume_data["leaf_id"].tolist()))
(220, [11, 42])
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.kernel.errors import ValueRefused
from ramure.gmap.kernel.frames import frame_from
from ramure.gmap.organs.fruit import build_fruit, resolve_params
from ramure.gmap.kernel.map3 import GMap3

if TYPE_CHECKING:
    from ramure.lsys.interpretation.turtle import Skeleton

#: Keys of an override besides fruit parameters (``defects``: defect specs recorded on the
#: fruit, carried in ``meta["fruits"]`` and applied by whoever shows the damaged fruit;
#: ``regions``: parts of the fruit regrown with their own parameters, see
#: :mod:`ramure.gmap.organs.regions`, applied when the fruit is built).
OVERRIDE_KEYS = ("preset", "seed", "size", "defects", "regions")


def _organ_arrays(positions, frames, sizes, leaf_ids):
    pos = np.asarray(positions, float).reshape(-1, 3)
    k = len(pos)
    try:
        fr = np.asarray(frames, float).reshape(k, 3, 3)
        size = np.asarray(sizes, float).reshape(k)
        leaf = np.asarray(leaf_ids, np.int64).reshape(k)
    except ValueError:
        raise ValueRefused(f"organ arrays disagree: {k} positions but frames, sizes or leaf ids of other lengths") from None
    bad = ~np.isfinite(size) | (size <= 0)
    if bad.any():
        raise ValueRefused(f"fruit sizes must be positive; leaf ids {leaf[bad].tolist()} have {size[bad].tolist()}")
    if len(np.unique(leaf)) != k:
        raise ValueRefused("two fruit organs share a history-leaf id")
    return pos, fr, size, leaf


def fruit_frame(turtle_frame: ArrayLike) -> np.ndarray:
    """Fruit frame (rows axis, L, U) for a turtle frame (rows H, L, U): axis = -H, L kept.

    >>> fruit_frame(np.eye(3)).tolist()
    [[-1.0, -0.0, -0.0], [0.0, 1.0, 0.0], [-0.0, -0.0, -1.0]]
    """
    t = np.asarray(turtle_frame, float)
    f = frame_from(t[..., 0, :], t[..., 1, :])  # re-orthonormalise the turtle's frame
    return np.stack([-f[..., 0, :], f[..., 1, :], -f[..., 2, :]], axis=-2)


def _fruit_specs(leaf, size, preset, seed, params, overrides):
    specs = []
    overrides = overrides or {}
    unknown = set(overrides) - set(leaf.tolist())
    if unknown:
        raise ValueRefused(f"overrides name leaf ids that are not fruit: {sorted(unknown)}")
    for lid, s in zip(leaf.tolist(), size.tolist()):
        spec = {"preset": preset, "seed": int(seed) + lid, "size": s, "params": dict(params or {})}
        for key, value in (overrides.get(lid) or {}).items():
            if key in OVERRIDE_KEYS:
                spec[key] = value
            else:
                spec["params"][key] = value
        if not float(spec["size"]) > 0:
            raise ValueRefused(f"fruit size must be positive, leaf {lid} has {spec['size']}")
        resolve_params(spec["preset"], **spec["params"])  # fail early, naming the problem
        specs.append(spec)
    return specs


def fruits_from_organs(
    positions: ArrayLike,
    frames: ArrayLike,
    sizes: ArrayLike,
    leaf_ids: ArrayLike,
    params: Mapping[str, Any] | None = None,
    preset: str = "round_tomato",
    seed: int = 0,
    volume_levels: int = 0,
    surface_levels: int = 0,
    overrides: Mapping[int, Mapping[str, Any]] | None = None,
    merge: bool = True,
) -> GMap3 | list[GMap3]:
    """Volumetric fruit for organs given as plain arrays; one merged :class:`GMap3` (or a list).

    ``positions`` (k, 3), ``frames`` (k, 3, 3) with rows H, L, U, ``sizes``
    (k,) and ``leaf_ids`` (k,) come straight from the turtle.  ``params``
    (fruit parameters, see :mod:`ramure.gmap.organs.fruit`) apply to every fruit;
    ``overrides`` maps a leaf id to changes for that fruit only: ``preset``,
    ``seed``, ``size`` or any fruit parameter.
    """
    pos, fr, size, leaf = _organ_arrays(positions, frames, sizes, leaf_ids)
    specs = _fruit_specs(leaf, size, preset, seed, params, overrides)
    tissues_random = int(volume_levels) > 0
    local = {}
    fruits = []
    for k, spec in enumerate(specs):  # one step per fruit, not per dart
        regions = list(spec.get("regions", []))
        key = (
            spec["preset"],
            tuple(sorted(spec["params"].items())),
            spec["seed"] if tissues_random or regions else None,
            repr(regions),
        )
        if key not in local:
            gm = build_fruit(
                spec["preset"],
                seed=spec["seed"],
                volume_levels=volume_levels,
                surface_levels=surface_levels,
                anchor="stem",
                regions=regions,
                **spec["params"],
            )
            local[key] = (gm, float(gm.meta["extent"]))  # without regions: they never move the rest
        gm, extent = local[key]
        gm = gm.copy()
        f = fruit_frame(fr[k])
        gm.transform(rotation=np.stack([f[1], f[2], f[0]]), scale=float(spec["size"]) / extent, offset=pos[k])
        gm.volume_data["leaf_id"][:] = leaf[k]
        gm.meta = {**gm.meta, "leaf_id": int(leaf[k]), "seed": int(spec["seed"]), "preset": spec["preset"]}
        fruits.append(gm)
    if not merge:
        return fruits
    merged = GMap3.merge(fruits) if fruits else GMap3()
    species = {(f.meta.get("species"), f.meta.get("ripeness")) for f in fruits}
    merged.meta = {
        # one species for the renderers when every fruit shares it (a mixed tree keeps the default)
        **(
            dict(zip(("species", "ripeness"), next(iter(species))))
            if len(species) == 1 and None not in next(iter(species))
            else {}
        ),
        "fruits": [
            {
                "leaf_id": int(lid),
                "preset": s["preset"],
                "seed": int(s["seed"]),
                "size": float(s["size"]),
                "params": s["params"],
                "defects": list(s.get("defects", [])),
                "regions": list(s.get("regions", [])),
            }
            for lid, s in zip(leaf, specs)
        ],
        "volume_levels": int(volume_levels),
        "surface_levels": int(surface_levels),
    }
    return merged


def fruits_from_skeleton(skeleton: Skeleton, kind: str = "Fruit", **kwargs: Any) -> GMap3 | list[GMap3]:
    """:func:`fruits_from_organs` for the organs of ``kind`` in ``skeleton.organs``.

    Duck-typed: ``skeleton.organs`` needs ``kind``, ``position``, ``frame``,
    ``size`` and ``leaf_id`` arrays (as :class:`ramure.lsys.Skeleton` has).
    """
    organs = skeleton.organs
    mask = np.asarray([str(k) == kind for k in organs.kind], bool)
    return fruits_from_organs(
        np.asarray(organs.position)[mask],
        np.asarray(organs.frame)[mask],
        np.asarray(organs.size)[mask],
        np.asarray(organs.leaf_id)[mask],
        **kwargs,
    )
