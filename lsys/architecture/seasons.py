"""Leaves that age, change colour and fall: the Open Markov Chain (Desbenoit 2006, ch. 4).

A leaf is in one of a few **states** (green, yellow, red, brown, dry), each pointing to a leaf
look. With environment ``e = (a, b)`` at the leaf — ``a`` the heat rate and ``b`` the
humidity rate, both in [0, 1] — and a time step ``t``:

* ``λ_i = ln 2 / τ_i(e)`` and ``P_ii = exp(−λ_i t)``: the probability of staying, so half the
  leaves of state ``i`` have left it after its half-life ``τ_i``;
* ``P_ij = (1 − P_ii) · X_ij(e)`` for ``j ≠ i`` with ``Σ_j X_ij = 1``;
* ``τ_i`` and ``X_ij`` are **bilinear** in ``(a, b)`` over four corner values given in the order
  ``(a, b) = (0, 0), (1, 0), (0, 1), (1, 1)``. The source labels its corners humid-cold,
  humid-hot, dry-cold, dry-hot, which makes ``b = 1`` *dry*; here ``b`` is **humidity** (1 is
  humid), stated once so the convention is consistent.

A leaf **detaches** with probability ``1 − D_i`` per step, where ``D_i(s, t) = exp(−δ_i t) ·
exp(−s²/σ_i²)`` is the stay-attached probability of the source (``δ_i = ln 2 / τ_fall_i``, ``s``
the wind strength, ``σ_i`` the wind sensitivity): in still air half the leaves of a state have
fallen after ``τ_fall_i``. A fallen leaf drops along one of the fall **motifs** (drop, flutter,
tumble, spiral: displacement per time step plus the wind) until it lands on the ground or on
the pile already there (a height map of cells; each landed leaf raises its cell by its
thickness), so leaves pile up downwind.

**Litter** (:func:`litter`, chosen here: the source's atlas leaves are scanned and folded by a
mass-spring model, and it compacts heaps by a physics run of up to 12 h): a fallen leaf is drawn
as an ovate blade (:func:`leaf_shape`) that rolls across and arches along as it dries, more each
step it has lain on the ground (``curl = t / (t + 4)`` of the full roll after ``t`` steps), and a
pile **compacts**: a leaf with ``k`` leaves above it in its cell keeps ``f + (1 − f) e^{−k/k₀}``
of its thickness (``f`` = :data:`COMPACTED`, ``k₀`` = :data:`COMPACTION_DEPTH`), so a pile of
``N`` leaves is lower than ``N`` thicknesses and its bottom layers are pressed flat.

**Random streams survive a regrow**: every draw is a counter-based hash of (seed, the leaf's
history-tree id, step, purpose), so a leaf keeps its fate when another part of the plant is
regrown, and only the regrown subtree's new leaves get new streams.

>>> chain = autumn_chain()
>>> np.allclose(chain.matrix(0.5, 0.5, 1.0).sum(axis=1), 1.0)
True
>>> import ramure
>>> result = age_leaves(ramure.derive("fruit_tree", n=5).skeleton().organs, chain, steps=16, seed=0)
>>> result.states.shape[0], bool(result.fallen.sum() > 0)
(17, True)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, cast

import numpy as np
from numpy.typing import ArrayLike

from ramure.errors import ValueRefused

if TYPE_CHECKING:
    from ..interpretation.turtle import Organs, Skeleton

LN2 = np.log(2.0)
MOTIFS = ("drop", "flutter", "tumble", "spiral")


def bilinear(corners: ArrayLike, a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """Bilinear interpolation of corner values ``(c00, c10, c01, c11)`` at ``(a, b)``.

    ``corners`` has shape (4, ...); ``a`` and ``b`` broadcast against the trailing shape.
    """
    c = np.asarray(corners, np.float64)
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    return (1 - a) * (1 - b) * c[0] + a * (1 - b) * c[1] + (1 - a) * b * c[2] + a * b * c[3]


@dataclass
class LeafChain:
    """An Open Markov Chain of leaf states.

    ``states``: names; ``half_life``: (k, 4) corner values of ``τ_i`` (time steps);
    ``targets``: (k, k, 4) corner values of ``X_ij`` (rows sum to 1 at every corner, the
    diagonal is 0; a state with no target is final); ``fall_half_life``: (k,) ``τ_fall_i``
    (``inf``: never falls); ``wind_sensitivity``: (k,) ``σ_i``; ``colors``: RGB per state.
    """

    states: tuple
    half_life: np.ndarray
    targets: np.ndarray
    fall_half_life: np.ndarray
    wind_sensitivity: np.ndarray
    colors: np.ndarray = field(default=None)  # type: ignore[arg-type]  # __post_init__ fills it

    def __post_init__(self) -> None:
        k = len(self.states)
        self.half_life = np.asarray(self.half_life, np.float64).reshape(k, 4)
        self.targets = np.asarray(self.targets, np.float64).reshape(k, k, 4)
        self.fall_half_life = np.asarray(self.fall_half_life, np.float64).reshape(k)
        self.wind_sensitivity = np.asarray(self.wind_sensitivity, np.float64).reshape(k)
        if self.colors is None:
            self.colors = np.full((k, 3), 0.5)
        self.check()

    def check(self) -> None:
        """Refuse half-lives <= 0, negative targets, rows that do not sum to 1 (naming the state)."""
        if not np.all(self.half_life > 0) or np.isnan(self.half_life).any():
            i = int(np.argwhere(~(self.half_life > 0))[0, 0])
            raise ValueRefused(f"state '{self.states[i]}': half-lives must be > 0")
        if not np.all(self.fall_half_life > 0) or not np.all(self.wind_sensitivity > 0):
            raise ValueRefused("fall half-lives and wind sensitivities must be > 0")
        if (self.targets < 0).any() or not np.all(np.isfinite(self.targets)):
            raise ValueRefused("transition weights must be finite and >= 0")
        sums = self.targets.sum(axis=1)  # (k, 4)
        for i, name in enumerate(self.states):
            if self.targets[i, i].any():
                raise ValueRefused(f"state '{name}': the weight of staying is set by the half-life, not X_ii")
            final = np.allclose(sums[i], 0.0)
            if not final and not np.allclose(sums[i], 1.0, atol=1e-9):
                raise ValueRefused(
                    f"state '{name}': its transition weights sum to {sums[i].round(6).tolist()} at the four corners, not 1"
                )

    def matrix(self, a: float, b: float, dt: float = 1.0) -> np.ndarray:
        """The transition matrix at one environment ``(a, b)`` for a step ``dt`` (rows sum to 1)."""
        return self.matrices(np.atleast_1d(a), np.atleast_1d(b), dt)[0]

    def matrices(self, a: np.ndarray, b: np.ndarray, dt: float = 1.0) -> np.ndarray:
        """(n, k, k) transition matrices, one per environment sample ``(a[i], b[i])``."""
        a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
        tau = bilinear(self.half_life.T, a[:, None], b[:, None])  # (n, k)
        x = bilinear(np.moveaxis(self.targets, 2, 0), a[:, None, None], b[:, None, None])  # (n, k, k)
        final = self.targets.sum(axis=(1, 2)) == 0
        stay = np.where(final[None, :], 1.0, np.exp(-LN2 / tau * dt))
        out = (1 - stay)[:, :, None] * x
        k = len(self.states)
        out[:, np.arange(k), np.arange(k)] = stay
        return out


def autumn_chain() -> LeafChain:
    """A default chain: green → yellow or red → brown → dry (final), heat speeds ageing.

    Half-lives (steps) at the corners (cold-dry, hot-dry, cold-humid, hot-humid); warmer
    places turn red rather than yellow; every state but green falls, dry leaves fastest.
    """
    states = ("green", "yellow", "red", "brown", "dry")
    half_life = [[6, 3, 8, 4], [4, 3, 5, 4], [4, 3, 5, 4], [3, 2, 4, 3], [1e9, 1e9, 1e9, 1e9]]
    k = len(states)
    targets = np.zeros((k, k, 4))
    targets[0, 1] = [0.8, 0.3, 0.9, 0.4]
    targets[0, 2] = [0.2, 0.7, 0.1, 0.6]
    targets[1, 3] = targets[2, 3] = targets[3, 4] = 1.0
    fall = [np.inf, 10, 10, 5, 2]
    colors = np.array([[0.25, 0.55, 0.18], [0.9, 0.75, 0.1], [0.8, 0.2, 0.1], [0.5, 0.3, 0.12], [0.6, 0.5, 0.35]])
    return LeafChain(states, half_life, targets, fall, [0.8, 0.8, 0.8, 0.6, 0.4], colors)  # type: ignore[arg-type]  # __post_init__ makes arrays


# -- counter-based random streams -----------------------------------------------------------
_PURPOSE = {"transition": 1, "detach": 2, "motif": 3, "phase": 4, "jitter": 5, "yaw": 6}


def leaf_uniform(seed: int, leaf_ids: np.ndarray, step: int, purpose: str) -> np.ndarray:
    """Uniform [0, 1) draws keyed by (seed, leaf id, step, purpose): the same leaf, the same draw.

    A SplitMix64 hash of the key, vectorised over leaves; independent of the other leaves, so a
    regrow elsewhere in the plant does not change a leaf's fate.
    """
    ids = np.asarray(leaf_ids, np.uint64)
    with np.errstate(over="ignore"):
        x = (np.uint64(seed & 0xFFFFFFFF) << np.uint64(32)) ^ (ids * np.uint64(0x9E3779B97F4A7C15))
        x ^= np.uint64((step * 0x85EBCA6B + _PURPOSE[purpose] * 0xC2B2AE35) & 0xFFFFFFFFFFFFFFFF)
        x = x + np.uint64(0x9E3779B97F4A7C15)
        x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        x = x ^ (x >> np.uint64(31))
    return (x >> np.uint64(11)).astype(np.float64) / float(1 << 53)


# -- the simulation ------------------------------------------------------------------------
@dataclass
class Season:
    """What :func:`age_leaves` did: ``states`` (steps+1, n) per step, ``fallen`` (n,) bool,
    ``fall_step`` (n,) (-1 still attached), ``ground`` (n,3) landing points (NaN if attached),
    ``motif`` (n,) index into :data:`MOTIFS`, and counts of the work done."""

    leaf_ids: np.ndarray
    states: np.ndarray
    fallen: np.ndarray
    fall_step: np.ndarray
    ground: np.ndarray
    motif: np.ndarray
    intersection_tests: int = 0
    trajectory_segments: int = 0
    cell: float = 0.25
    thickness: float = 0.02
    seed: int = 0

    def colors(self, chain: LeafChain, step: int = -1) -> np.ndarray:
        return chain.colors[self.states[step]]

    def facts(self, chain: LeafChain) -> dict:
        last = self.states[-1]
        return {
            "leaves": len(self.leaf_ids),
            "steps": len(self.states) - 1,
            "fallen_leaves": int(self.fallen.sum()),
            "fallen_per_step": np.bincount(self.fall_step[self.fallen] + 1, minlength=len(self.states))[1:].cumsum().tolist(),
            "states": {name: int((last == i).sum()) for i, name in enumerate(chain.states)},
            "intersection_tests": int(self.intersection_tests),
            "trajectory_segments": int(self.trajectory_segments),
        }


def age_leaves(
    organs: Skeleton | Organs | tuple[ArrayLike, ArrayLike],
    chain: LeafChain,
    steps: int = 16,
    seed: int = 0,
    heat: float = 0.5,
    humidity: float = 0.5,
    wind: ArrayLike = (0.0, 0.0),
    dt: float = 1.0,
    ground_cell: float = 0.25,
    thickness: float = 0.02,
) -> Season:
    """Age, detach and drop the ``Leaf`` organs of a plant for ``steps`` steps.

    ``organs`` is a derived plant's :class:`~ramure.lsys.interpretation.turtle.Skeleton` (its ``Leaf`` and
    surface organs and its polygons age: :func:`plant_leaves`), its ``Organs`` (organs only),
    or a tuple ``(leaf_ids, positions)``. ``heat`` and ``humidity`` are numbers or per-leaf arrays in
    [0, 1]; ``wind`` is the horizontal wind (x, y) in units per step, or a strength along x
    (its length is the wind strength ``s``). Deterministic for a seed, leaf by leaf.
    A plant (skeleton or organs) without any leaf is refused with :class:`ValueRefused`; an
    explicit empty ``(leaf_ids, positions)`` tuple gives an empty season.
    """
    ids, positions = _leaves(organs)
    steps, dt, wind_xy = _check_run(steps, dt, wind)
    n = len(ids)
    a, b = _environment(heat, n, "heat"), _environment(humidity, n, "humidity")
    states, fall_step = age_states(ids, a, b, chain, steps, seed, dt, float(np.hypot(*wind_xy)))
    fallen = fall_step >= 0
    motif = np.minimum((leaf_uniform(seed, ids, 0, "motif") * len(MOTIFS)).astype(np.int64), len(MOTIFS) - 1)
    ground = np.full((n, 3), np.nan)
    tests = segments = 0
    if fallen.any():
        ground[fallen], tests, segments = _drop(
            ids[fallen], positions[fallen], fall_step[fallen], motif[fallen], wind_xy, seed, ground_cell, thickness
        )
    return Season(ids, states, fallen, fall_step, ground, motif, tests, segments, ground_cell, thickness, seed)


def age_states(
    ids: np.ndarray,
    heat: np.ndarray,
    humidity: np.ndarray,
    chain: LeafChain,
    steps: int,
    seed: int = 0,
    dt: float = 1.0,
    wind_strength: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The Markov part of :func:`age_leaves`: states (steps+1, n) and the step each leaf fell (-1: none).

    One vectorised pass per step: a uniform draw per leaf against the cumulative row of its
    state, then a detachment draw against its new state's stay-attached probability.
    """
    n = len(ids)
    cumulative = np.cumsum(chain.matrices(heat, humidity, dt), axis=2)  # (n, k, k): constant environment
    stay = np.exp(-LN2 / chain.fall_half_life * dt) * np.exp(-(wind_strength**2) / chain.wind_sensitivity**2)
    last = len(chain.states) - 1
    states = np.zeros((steps + 1, n), np.int64)
    fall_step = np.full(n, -1, np.int64)
    attached = np.ones(n, bool)
    rows = np.arange(n)
    for t in range(1, steps + 1):
        u = leaf_uniform(seed, ids, t, "transition")
        states[t] = np.minimum((u[:, None] >= cumulative[rows, states[t - 1]]).sum(axis=1), last)
        drop = attached & (leaf_uniform(seed, ids, t, "detach") >= stay[states[t]])
        fall_step[drop] = t
        attached &= ~drop
    return states, fall_step


def plant_leaves(skeleton: Skeleton | Organs) -> tuple[np.ndarray, np.ndarray]:
    """``(leaf_ids, positions)`` of every leaf of a derived plant: ``Leaf`` organs, surface
    organs (``~leaf``, ``~petal``, and so on) and filled polygons (at their centroid; a
    polygon's id is its ``{`` module's history leaf, the id its triangles carry in the mesh).
    Accepts a :class:`~ramure.lsys.interpretation.turtle.Skeleton` or its :class:`~ramure.lsys.interpretation.turtle.Organs`."""
    organs = cast("Organs", getattr(skeleton, "organs", skeleton))
    kind = np.asarray(organs.kind, dtype=object)
    leaf = np.array([k == "Leaf" or str(k).startswith("~") for k in kind], bool)
    id_parts = [np.asarray(organs.leaf_id, np.int64)[leaf]]
    position_parts = [np.asarray(organs.position, np.float64).reshape(-1, 3)[leaf]]
    polygons = getattr(skeleton, "polygons", None)
    if polygons is not None and len(polygons):
        sizes = np.maximum(polygons.sizes, 1)
        owner = np.repeat(np.arange(len(polygons)), polygons.sizes)
        centre = np.stack([np.bincount(owner, polygons.points[:, k], minlength=len(polygons)) for k in range(3)], 1)
        id_parts.append(np.asarray(polygons.leaf_id, np.int64))
        position_parts.append(centre / sizes[:, None])
    ids, positions = np.concatenate(id_parts), np.concatenate(position_parts)
    _, first = np.unique(ids, return_index=True)  # one leaf per history leaf (a '{' drawn twice is one leaf)
    first = np.sort(first)
    return ids[first], positions[first]


#: The refusal for a plant that has no leaves (issue 40: ``autumn`` on such a plant gave 0 leaves, exit 0).
NO_LEAVES = (
    "this plant has no leaves to age: it draws no Leaf module, no ~surface organ (~leaf, ~petal, ...) "
    "and no filled polygon { ... }; add leaves to the grammar, or choose a plant that has them"
)


def _leaves(organs):
    if isinstance(organs, tuple):
        ids, positions = organs
    else:
        ids, positions = plant_leaves(organs)
        if len(ids) == 0:  # a plant with nothing to age: say so instead of an empty autumn
            raise ValueRefused(NO_LEAVES)
    ids = np.asarray(ids, np.int64)
    positions = np.asarray(positions, np.float64).reshape(len(ids), 3)
    if len(ids) > 50_000_000:
        raise ValueRefused(f"{len(ids)} leaves are more than the limit of 50,000,000")
    return ids, positions


def _check_run(steps: int, dt: float, wind: ArrayLike) -> tuple[int, float, np.ndarray]:
    if int(steps) != steps or steps < 0 or steps > 100_000:
        raise ValueRefused(f"steps must be a whole number in 0..100000, not {steps}")
    if not (np.isfinite(dt) and dt > 0):
        raise ValueRefused(f"the time step must be > 0, not {dt}")
    w = np.asarray(wind, np.float64)
    if w.ndim == 0:  # a strength along +x
        if not np.isfinite(w) or w < 0:
            raise ValueRefused(f"the wind strength must be a finite number >= 0, not {float(w)}")
        w = np.array([float(w), 0.0])
    if w.shape != (2,) or not np.all(np.isfinite(w)):
        raise ValueRefused("wind is a strength >= 0 or a finite horizontal vector (x, y)")
    return int(steps), float(dt), w


def _environment(value, n, name):
    v = np.broadcast_to(np.asarray(value, np.float64), (n,)).copy() if np.ndim(value) == 0 else np.asarray(value, np.float64)
    if v.shape != (n,):
        raise ValueRefused(f"the {name} map has {v.size} values for {n} leaves")
    if np.isnan(v).any() or v.min(initial=0) < 0 or v.max(initial=0) > 1:
        raise ValueRefused(f"{name} values must be numbers in [0, 1] (no NaN)")
    return v


def _motif_offsets(motif, phase, k):
    """Displacement of step ``k`` of each leaf's fall motif (x, y, z), per unit of fall speed."""
    angle = 2 * np.pi * (phase + 0.15 * k)
    sway = np.stack([np.cos(angle), np.sin(angle)], axis=1)
    lateral = np.select([motif == 1, motif == 2, motif == 3], [0.35, 0.2, 0.25], 0.0)[:, None] * sway
    flip = np.where(motif == 2, np.sign(np.sin(angle * 2)) * 0.1, 0.0)[:, None] * sway[:, ::-1]
    down = np.select([motif == 0, motif == 1, motif == 2, motif == 3], [0.5, 0.22, 0.3, 0.28])
    return np.concatenate([lateral + flip, -down[:, None]], axis=1)


# -- litter: fallen leaves drawn curled, in piles that compact --------------------------------
#: The share of its thickness a deeply buried leaf keeps, and the number of leaves above it
#: over which it is pressed (an e-folding count): chosen here, see the module docstring.
COMPACTED = 0.35
COMPACTION_DEPTH = 4.0
#: The roll of a fully dried blade across its width, in radians from the midrib to an edge.
FULL_ROLL = 1.3


def leaf_shape(
    length: float = 1.0, width: float = 0.5, roll: float = 0.0, arch: float = 0.0, rows: int = 9, cols: int = 7
) -> tuple[np.ndarray, np.ndarray]:
    """An ovate leaf blade as triangles: ``(points (k, 3), triangles (m, 3))``, the midrib along x
    from the petiole (``x = -length/2``) to the tip, lying on z = 0 when flat.

    ``roll`` bends the blade across its midrib: the edges turn up by ``roll`` radians (the blade
    is bent, not stretched, so its area stays that of the flat leaf); ``arch`` lifts tip and
    petiole by ``arch * length / 4`` each. Widest a little before the middle:
    ``half-width(u) = width/2 * sin(pi u)^0.7 * (1 - u/4)``, ``u`` in [0, 1] along the midrib.
    """
    points = _blades(length, width, np.array([float(roll)]), np.array([float(arch)]), rows, cols)[0]
    a = (np.arange(rows - 1)[:, None] * cols + np.arange(cols - 1)[None, :]).ravel()
    quads = np.stack([a, a + 1, a + cols + 1, a + cols], axis=1)
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    corners = points[triangles]
    area = np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    return points, triangles[area > 1e-15 * max(length, width) ** 2]  # the petiole and tip rows meet in a point


def _blades(length, width, roll, arch, rows=9, cols=7):
    """The points of ``len(roll)`` blades at once, (n, rows * cols, 3) (see :func:`leaf_shape`)."""
    u = np.linspace(0.0, 1.0, rows)
    v = np.linspace(-1.0, 1.0, cols)
    half = 0.5 * width * np.sin(np.pi * u) ** 0.7 * (1 - 0.25 * u)
    x = np.broadcast_to(((u - 0.5) * length)[None, :, None], (len(roll), rows, cols))
    across = np.broadcast_to(half[None, :, None] * v[None, None, :], x.shape)
    bend = np.maximum(roll, 1e-9)[:, None, None] / np.maximum(half, 1e-12)[None, :, None]
    angle = across * bend  # the curvature that turns each row's edge up by ``roll``
    y, z = np.sin(angle) / bend, (1 - np.cos(angle)) / bend
    z = z + arch[:, None, None] * x**2 / length
    return np.stack([x, y, z], axis=-1).reshape(len(roll), -1, 3)


def pile_heights(season: Season, step: int = -1) -> np.ndarray:
    """The height of each leaf fallen by ``step`` on its compacted pile (NaN for the others).

    Leaves share a pile when they landed in one ``season.cell`` square; they lie in the order
    they landed, each pressed by the leaves above it (see the module docstring), so a pile's top
    is ``sum_k t (f + (1 - f) exp(-k / k0))`` over its leaves, ``k`` counted from the top.
    """
    step = len(season.states) - 1 if step < 0 else step
    down = np.flatnonzero(season.fallen & (season.fall_step <= step))
    out = np.full(len(season.leaf_ids), np.nan)
    if not len(down):
        return out
    ground = season.ground[down]
    keys = np.floor(ground[:, :2] / season.cell).astype(np.int64)
    order = np.lexsort((ground[:, 2], keys[:, 1], keys[:, 0]))  # by square, bottom (first landed) to top
    keys, ground, down = keys[order], ground[order], down[order]
    new_pile = np.r_[True, (keys[1:] != keys[:-1]).any(axis=1)]
    pile = np.cumsum(new_pile) - 1
    starts = np.flatnonzero(new_pile)
    size = np.diff(np.r_[starts, len(down)])[pile]
    above = size - 1 - (np.arange(len(down)) - starts[pile])
    pressed = season.thickness * (COMPACTED + (1 - COMPACTED) * np.exp(-above / COMPACTION_DEPTH))
    below = np.cumsum(pressed) - pressed
    base = below[starts][pile]  # what the earlier piles add to the running sum
    out[down] = (below - base) + pressed / 2 + _ground_level(ground, pile, starts, season.thickness)
    return out


def _ground_level(ground, pile, starts, thickness):
    """Where each pile stands: the first leaf's landing height less half a thickness (0 on open ground)."""
    return np.maximum(ground[starts, 2] - thickness / 2, 0.0)[pile]


def litter(season: Season, step: int = -1, size: float = 0.12) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The fallen leaves at ``step`` as one triangle mesh: ``(points, triangles, leaf)`` where
    ``leaf`` (m,) is each triangle's index into ``season.leaf_ids``.

    Each leaf is a :func:`leaf_shape` ``size`` long, turned by a yaw drawn from its own stream
    (it keeps it through a regrow), rolled and arched by the steps it has lain on the ground,
    standing on its compacted pile (:func:`pile_heights`).
    """
    step = len(season.states) - 1 if step < 0 else step
    z = pile_heights(season, step)
    down = np.flatnonzero(~np.isnan(z))
    if not len(down):
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros(0, np.int64)
    lying = step - season.fall_step[down]
    curl = lying / (lying + 4.0)
    yaw = 2 * np.pi * leaf_uniform(season.seed, season.leaf_ids[down], 0, "yaw")
    flat, triangles = leaf_shape(size, size / 2)
    cos, sin = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    blades = _blades(size, size / 2, FULL_ROLL * curl, 0.3 * curl)
    x, y = blades[..., 0], blades[..., 1]
    turned = np.stack([x * cos - y * sin, x * sin + y * cos, blades[..., 2]], axis=-1)
    centre = np.column_stack([season.ground[down, :2], z[down]])
    points = (turned + centre[:, None, :]).reshape(-1, 3)
    all_triangles = (triangles[None] + len(flat) * np.arange(len(down))[:, None, None]).reshape(-1, 3)
    return points, all_triangles, np.repeat(down, len(triangles))


def _drop(ids, start, fall_step, motif, wind, seed, cell, thickness):
    """Let leaves fall in the order they detached and land on the ground or on the pile.

    The pile is a height map of ``cell``-sized squares; a leaf lands when it comes down to the
    top of its square (each landing raises the square by ``thickness``). Only leaves low enough
    to reach a pile are tested, one by one, so leaves stack in the order they arrive. Leaves do
    not collide with branches on the way down (a simplification of the source's cylinders).
    """
    order = np.lexsort((ids, fall_step))
    ids, pos, motif = ids[order], start[order].copy(), motif[order]
    phase = leaf_uniform(seed, ids, 0, "phase")
    landed = np.zeros(len(ids), bool)
    heights: dict[tuple[int, int], float] = {}
    highest = 0.0
    tests = segments = 0
    for k in range(10_000):
        moving = np.flatnonzero(~landed)
        if not len(moving):
            break
        step = _motif_offsets(motif[moving], phase[moving], k)
        step[:, :2] += wind
        pos[moving] += step
        segments += len(moving)
        low = moving[pos[moving, 2] <= highest + thickness]
        for i in low.tolist():  # land one by one so a pile grows leaf on leaf
            key = (int(np.floor(pos[i, 0] / cell)), int(np.floor(pos[i, 1] / cell)))
            top = heights.get(key, 0.0)
            tests += 1
            if pos[i, 2] <= top:
                pos[i, 2] = top + thickness / 2
                heights[key] = top + thickness
                highest = max(highest, top + thickness)
                landed[i] = True
    out = np.empty_like(pos)
    out[order] = pos
    return out, tests, segments
