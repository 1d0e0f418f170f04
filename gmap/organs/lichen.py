"""Lichen that grows on a surface: Open-DLA (Desbenoit, Galin, Akkouche 2004; thesis ch. 3).

Clusters start from **seeds** (random surface points kept with a painted adhesion probability).
A particle ``p_i`` of a cluster emits ``p_j`` at ``2r + ε`` on the surface; ``p_j`` walks in
steps of ``l``, its direction turning by at most ``±turn`` each step, across triangles (a
direction entering a triangle of normal ``n2`` becomes ``n2 ∧ (d ∧ n2)``). When a step would
overlap a particle, ``p_j`` stops where it was; if it then touches its own cluster it is kept
with probability ``P = A · E`` — ``A = α + (1 − α) exp(−σ (n − τ)²)`` with ``n`` the particles
within ``ρ``, ``E = min(I, D, H)`` the habit's responses to indirect light, direct light and
humidity — else destroyed; touching another cluster or straying further than ``kill`` from its
emitter destroys it. Each emitter holds two tokens ``a``, ``b``: a failed attempt — a birth
that already touches the cluster (the source's case) or a walker that did not join (added
here, so an emitter in a hostile place retires instead of trying for ever) — costs an ``a``;
when ``a`` runs out the emitter loses a ``b`` and gets its ``a`` back; an emitter with no ``b``
left is retired, and growth stops when every emitter is retired.

Collisions: the source tests a particle only against the particles of its triangle's 1-ring,
which is exact only while ``2r + l`` is below the triangles' heights; on real meshes (slivers,
fine tessellations) it misses contacts. Here each particle is tested against the particles of
the 27 cells of a hashed grid of cell size ``max(2r + l, ρ)`` around it: constant time per
test like the 1-ring, and exact for every mesh (:func:`neighbours` is tested against brute
force).

Defaults (spec "Decisions and corrections" 1; the source gives none for some): ``r = 0.5``
(mm on bark), ``ε = r/2``, ``l = r``, ``turn = 30°``, ``ρ = 2r`` (compact; 3r for dendritic
habits), ``σ = 1``, ``τ = 4``, ``a = 20``, ``b = 200``; a walker is destroyed after 400 steps or
20r from its emitter (the source gives no kill radius; the walk is correlated, ±30° a step, so
it needs room to come back). Lengths are in the mesh's units.

Environment, chosen here (the source samples a sun path and a sky by Monte Carlo): direct light
``D_light = max(0, n · sun)``, indirect light ``(1 + n · up) / 2`` (open sky above), humidity a
painted per-vertex map (default 0.5). Each **habit** maps them through piecewise-linear
responses: crustose tolerates direct light, foliose needs humidity, fruticose likes indirect
light and humidity. **Age classes**: a particle's age is the order it joined its cluster; old
particles are inside, young ones on the rim; :func:`age_classes` bins them and draws atlas
models from disjoint intervals ``[a_i, b_i)`` covering [0, 1).

>>> import pyvista as pv
>>> from ramure.gmap.organs.trimesh import from_polydata
>>> stone = from_polydata(pv.Sphere(radius=5, theta_resolution=40, phi_resolution=40))
>>> growth = grow_lichen(stone, clusters=3, particles=150, r=0.05, seed=1)
>>> growth.count, len(set(growth.cluster.tolist()))
(150, 3)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypedDict

import numpy as np
from numpy.typing import ArrayLike

from ramure.gmap.organs import _dla_kernel as kernel
from ramure.gmap.kernel.errors import GMapError
from ramure.gmap.organs.trimesh import TriMesh

if TYPE_CHECKING:
    import pyvista as pv


class Habit(TypedDict):
    """A habit's responses, each ``(x points, y values)`` of a piecewise-linear curve, and its
    aggregation defaults ``rho`` (in units of r), ``sigma``, ``tau``."""

    indirect: tuple[list[float], list[float]]
    direct: tuple[list[float], list[float]]
    humidity: tuple[list[float], list[float]]
    rho: float
    sigma: float
    tau: float


#: Responses per habit: (x points, y values) for indirect light, direct light, humidity.
HABITS: dict[str, Habit] = {
    "crustose": {
        "indirect": ([0, 1], [0.6, 1.0]),
        "direct": ([0, 1], [1.0, 0.8]),
        "humidity": ([0, 0.2, 1], [0.3, 0.9, 1.0]),
        "rho": 2.0,
        "sigma": 1.0,
        "tau": 4.0,
    },
    "foliose": {
        "indirect": ([0, 1], [0.4, 1.0]),
        "direct": ([0, 0.5, 1], [1.0, 0.6, 0.2]),
        "humidity": ([0, 0.4, 1], [0.0, 0.5, 1.0]),
        "rho": 2.5,
        "sigma": 0.6,
        "tau": 5.0,
    },
    "fruticose": {
        "indirect": ([0, 1], [0.2, 1.0]),
        "direct": ([0, 1], [0.9, 0.3]),
        "humidity": ([0, 0.5, 1], [0.1, 0.7, 1.0]),
        "rho": 3.0,
        "sigma": 0.3,
        "tau": 3.0,
    },
}
MAX_PARTICLES = 2_000_000


@dataclass
class Lichen:
    """Particles: ``position`` (m, 3) on the surface, ``triangle`` (m,), ``cluster`` (m,), ``age``
    (m,) (order of joining, 0 = the seed), plus ``r`` and the number of distance tests."""

    position: np.ndarray
    triangle: np.ndarray
    cluster: np.ndarray
    age: np.ndarray
    r: float
    intersection_tests: int

    @property
    def count(self) -> int:
        return len(self.position)

    def facts(self) -> dict[str, int]:
        return {
            "clusters": int(len(np.unique(self.cluster))),
            "particles": self.count,
            "intersection_tests": int(self.intersection_tests),
        }


def environment(
    mesh: TriMesh, habit: str = "crustose", sun: ArrayLike = (0.3, -0.4, 0.87), humidity: ArrayLike | None = None
) -> np.ndarray:
    """``E = min(I, D, H)`` per vertex for a habit (see the module docstring)."""
    if habit not in HABITS:
        raise GMapError(f"unknown lichen habit {habit!r} (known: {', '.join(HABITS)})")
    curves = HABITS[habit]
    normals = _vertex_normals(mesh)
    towards_sun = np.asarray(sun, np.float64)
    towards_sun = towards_sun / np.linalg.norm(towards_sun)
    direct = np.clip(normals @ towards_sun, 0, 1)
    indirect = (1 + normals[:, 2]) / 2
    wet = np.full(len(mesh.points), 0.5) if humidity is None else _map(humidity, len(mesh.points), "humidity")
    parts = [np.interp(indirect, *curves["indirect"]), np.interp(direct, *curves["direct"]), np.interp(wet, *curves["humidity"])]
    return np.minimum.reduce(parts)


def accessibility(mesh: TriMesh, reference: float | None = None, iterations: int = 14) -> np.ndarray:
    """Tangent-sphere accessibility per vertex (Miller 1994), in [0, 1].

    A vertex's accessibility is the radius of the largest sphere that touches the surface there
    from outside (centre ``p + r n``) and holds none of the surface inside, over ``reference``
    (default: half the bounding-box diagonal), capped at 1: deep creases and the stem cavity of a
    fruit are near 0, open convex skin is 1.  The emptiness test uses the surface's vertices, edge
    midpoints and triangle centroids in a k-d tree, with a 0.5 % tolerance for the facets; the radius
    is found by bisection on a log scale from a tenth of the mean edge length (monotone: the tangent
    spheres at one point with one normal are nested).
    """
    from scipy.spatial import cKDTree

    points, tris = mesh.points, mesh.triangles
    lo, hi = points.min(axis=0), points.max(axis=0)
    reference = float(np.linalg.norm(hi - lo)) / 2 if reference is None else float(reference)
    if not (np.isfinite(reference) and reference > 0):
        raise GMapError(f"the accessibility reference radius must be > 0, not {reference}")
    corners = points[tris]
    samples = np.concatenate([points, corners.mean(axis=1), (corners + np.roll(corners, 1, axis=1)).reshape(-1, 3) / 2])
    tree = cKDTree(samples)
    normals = _vertex_normals(mesh)
    edge = float(np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).mean())
    radius = np.full(len(points), reference)
    hidden = np.flatnonzero(~_empty(tree, points, normals, radius))  # the others are open at the reference
    low = np.full(len(hidden), np.log(min(edge / 10, reference)))
    high = np.full(len(hidden), np.log(reference))
    for _ in range(iterations):
        mid = (low + high) / 2
        fits = _empty(tree, points[hidden], normals[hidden], np.exp(mid))
        low, high = np.where(fits, mid, low), np.where(fits, high, mid)
    radius[hidden] = np.exp(low)
    return np.clip(radius / reference, 0.0, 1.0)


def _empty(tree, points, normals, radius) -> np.ndarray:
    """Whether the sphere of ``radius`` (one per point) tangent at each point outside holds no sample."""
    if not len(points):
        return np.zeros(0, bool)
    distance, _ = tree.query(points + normals * radius[:, None], distance_upper_bound=float(radius.max()))
    return distance >= 0.995 * radius


def seed_map(
    mesh: TriMesh,
    habit: str = "crustose",
    target: float | None = 0.45,
    width: float = 0.2,
    humidity: ArrayLike | None = None,
    sun: ArrayLike = (0.3, -0.4, 0.87),
    reference: float | None = None,
) -> np.ndarray:
    """Where spores stay, per vertex in [0, 1]: the habit's light and humidity response
    :func:`environment` times an accessibility band around ``target`` (the spec: spores are
    dropped where accessibility is too high or too low; crustose lichen on stone at about 0.45),
    ``exp(-((a - target) / width)^2)``.  ``target=None`` leaves accessibility out (light and
    humidity only).  Pass the result as ``adhesion`` to :func:`grow_lichen`.  The map is scaled
    so its best place is 1: on a surface whose accessibility is the same everywhere (a convex
    fruit, a smooth stone) light and humidity alone decide.  A map that is 0 everywhere is refused.
    """
    env = environment(mesh, habit, sun, humidity)
    if target is None:
        weights = env
    else:
        if not (0 <= target <= 1 and width > 0):
            raise GMapError(f"the accessibility target must be in [0, 1] and the width > 0, not {target}, {width}")
        band = np.exp(-(((accessibility(mesh, reference) - target) / width) ** 2))
        weights = env * band
    if not weights.max() > 0:
        what = "light and humidity" if target is None else f"accessibility near {target:g}, light and humidity"
        raise GMapError(f"no place on this surface suits {habit} lichen ({what}); seed anywhere or paint where it may start")
    return np.clip(weights / weights.max(), 0.0, 1.0)


def _vertex_normals(mesh: TriMesh) -> np.ndarray:
    acc = np.zeros_like(mesh.points)
    for k in range(3):
        np.add.at(acc, mesh.triangles[:, k], mesh.normals * mesh.areas[:, None])
    return acc / np.maximum(np.linalg.norm(acc, axis=1, keepdims=True), 1e-300)


def _map(values: ArrayLike, n: int, name: str) -> np.ndarray:
    v = np.asarray(values, np.float64)
    if v.shape != (n,):
        raise GMapError(f"the {name} map has {v.size} values for a mesh of {n} vertices")
    if np.isnan(v).any() or v.min() < 0 or v.max() > 1:
        raise GMapError(f"the {name} map must hold numbers in [0, 1] (no NaN)")
    return v


def grow_lichen(
    mesh: TriMesh,
    clusters: int = 5,
    particles: int = 500,
    r: float = 0.5,
    eps: float | None = None,
    step: float | None = None,
    turn: float = 30.0,
    rho: float | None = None,
    alpha: float = 0.2,
    sigma: float | None = None,
    tau: float | None = None,
    habit: str = "crustose",
    env: ArrayLike | None = None,
    adhesion: ArrayLike | None = None,
    a_tokens: int = 20,
    b_tokens: int = 200,
    max_steps: int = 400,
    kill: float | None = None,
    seed: int = 0,
) -> Lichen:
    """Grow ``clusters`` lichen clusters up to ``particles`` particles in all (see the module docstring).

    ``env`` overrides E per vertex (default: :func:`environment` of the habit); ``adhesion``
    (per vertex, [0, 1]) is the painted seeding probability. ``rho``, ``sigma``, ``tau`` default
    to the habit's (ρ in units of r).
    """
    eps = r / 2 if eps is None else eps
    step = r if step is None else step
    preset = HABITS.get(habit)
    if preset is None:
        raise GMapError(f"unknown lichen habit {habit!r} (known: {', '.join(HABITS)})")
    rho = preset["rho"] * r if rho is None else rho
    sigma = preset["sigma"] if sigma is None else sigma
    tau = preset["tau"] if tau is None else tau
    kill = 20 * r if kill is None else kill
    _check(mesh, clusters, particles, r, eps, step, turn, alpha, sigma, rho, a_tokens, b_tokens)
    env = environment(mesh, habit) if env is None else _map(env, len(mesh.points), "environment")
    rng = np.random.default_rng(seed)
    seed_tri, seed_pos = _seeds(mesh, clusters, adhesion, r, rng)
    n_seeds = len(seed_tri)
    h, mask = _grid(r, step, rho, particles)
    state = _state(particles, seed_pos, seed_tri, a_tokens, b_tokens, h, mask)
    tests = np.zeros(1, np.int64)
    count = kernel.grow(
        mesh.points,
        mesh.triangles,
        mesh.across,
        mesh.normals,
        h,
        mask,
        env,
        state["particles"],
        state["tri"],
        state["cluster"],
        n_seeds,
        state["a"],
        state["b"],
        state["head"],
        state["next"],
        float(r),
        float(eps),
        float(step),
        np.radians(turn),
        float(rho),
        float(alpha),
        float(sigma),
        float(tau),
        int(max_steps),
        float(kill),
        int(particles),
        int(rng.integers(2**31 - 1)),
        tests,
        int(a_tokens),
        int(b_tokens),
    )
    cluster = state["cluster"][:count]
    age = np.zeros(count, np.int64)
    for c in np.unique(cluster):
        members = np.flatnonzero(cluster == c)
        age[members] = np.arange(len(members))
    return Lichen(state["particles"][:count].copy(), state["tri"][:count].copy(), cluster.copy(), age, float(r), int(tests[0]))


def _check(mesh, clusters, particles, r, eps, step, turn, alpha, sigma, rho, a_tokens, b_tokens):
    for name, value in (("r", r), ("eps", eps), ("step l", step), ("rho", rho)):
        if not (np.isfinite(value) and value > 0):
            raise GMapError(f"{name} must be a number > 0, not {value}")
    if not (0 <= alpha <= 1):
        raise GMapError(f"alpha (the aggregation floor) must be in [0, 1], not {alpha}")
    if not (0 <= turn <= 180) or not (np.isfinite(sigma) and sigma >= 0):
        raise GMapError("the turn angle must be in [0, 180] degrees and sigma >= 0")
    if not (1 <= clusters <= particles <= MAX_PARTICLES) or a_tokens < 1 or b_tokens < 1:
        raise GMapError(f"need 1 <= clusters <= particles <= {MAX_PARTICLES:,} and tokens >= 1")


def _grid(r, step, rho, capacity):
    """Cell size and hash mask of the collision grid."""
    h = max(2 * r + step, rho)
    mask = (1 << int(np.ceil(np.log2(max(2 * capacity, 64))))) - 1
    return float(h), int(mask)


def neighbours(points: np.ndarray, query: np.ndarray, r: float, step: float, rho: float) -> tuple[np.ndarray, np.ndarray]:
    """For each query point: distance to the nearest of ``points`` and the count within ``rho``,
    through the collision grid (what the growth uses; equals brute force up to the cell size)."""
    h, mask = _grid(r, step, rho, len(points))
    head = np.full(mask + 1, -1, np.int64)
    nxt = np.full(len(points), -1, np.int64)
    for i, p in enumerate(np.asarray(points, np.float64)):
        key = kernel.cell_key(p, h, mask)
        nxt[i] = head[key]
        head[key] = i
    out = [kernel.nearest(np.asarray(q, np.float64), head, nxt, np.asarray(points, np.float64), h, mask, rho) for q in query]
    return np.array([o[0] for o in out]), np.array([o[2] for o in out])


def _seeds(mesh, clusters, adhesion, r, rng):
    """Seed points, kept with the painted adhesion probability, at least 2r apart."""
    weights = None
    if adhesion is not None:
        paint = _map(adhesion, len(mesh.points), "adhesion")
        weights = paint[mesh.triangles].mean(axis=1)
        if not weights.any():
            raise GMapError("the adhesion map is zero everywhere: paint where lichen may grow")
    tris: list[int] = []
    points: list[np.ndarray] = []
    for _ in range(200):
        tri, pos = mesh.random_points(4 * clusters, rng, weights)
        if adhesion is not None:
            keep = rng.random(len(tri)) < mesh.interpolate(paint, tri, pos)
            tri, pos = tri[keep], pos[keep]
        for t, p in zip(tri.tolist(), pos):
            if all(np.linalg.norm(p - q) >= 4 * r for q in points):
                tris.append(t)
                points.append(p)
            if len(points) == clusters:
                return np.array(tris, np.int64), np.array(points)
    raise GMapError(f"could not place {clusters} seeds at least 4r apart on this surface")


def _state(capacity, seed_pos, seed_tri, a_tokens, b_tokens, h, mask):
    n = len(seed_tri)
    particles = np.zeros((capacity, 3))
    particles[:n] = seed_pos
    tri = np.full(capacity, -1, np.int64)
    tri[:n] = seed_tri
    cluster = np.full(capacity, -1, np.int64)
    cluster[:n] = np.arange(n)
    head = np.full(mask + 1, -1, np.int64)
    nxt = np.full(capacity, -1, np.int64)
    for i in range(n):
        key = kernel.cell_key(particles[i], h, mask)
        nxt[i] = head[key]
        head[key] = i
    return {
        "particles": particles,
        "tri": tri,
        "cluster": cluster,
        "head": head,
        "next": nxt,
        "a": np.full(capacity, a_tokens, np.int64),
        "b": np.full(capacity, b_tokens, np.int64),
    }


def age_classes(lichen: Lichen, classes: int = 3) -> np.ndarray:
    """Age class per particle: 0 the oldest third of its cluster (inside) ... classes-1 the rim."""
    out = np.zeros(lichen.count, np.int64)
    for c in np.unique(lichen.cluster):
        members = np.flatnonzero(lichen.cluster == c)
        out[members] = np.minimum(lichen.age[members] * classes // max(len(members), 1), classes - 1)
    return out


def atlas_models(lichen: Lichen, intervals: Sequence[Sequence[tuple[float, float]]], seed: int = 0) -> np.ndarray:
    """Draw an atlas model per particle: ``intervals[c]`` lists ``(a_i, b_i)`` for age class ``c``;
    the intervals of a class are disjoint and cover [0, 1); returns the model index in its class."""
    classes = age_classes(lichen, len(intervals))
    u = np.random.default_rng(seed).random(lichen.count)
    out = np.zeros(lichen.count, np.int64)
    for c, bounds in enumerate(intervals):
        edges = np.asarray(bounds, np.float64)
        order = np.argsort(edges[:, 0])
        lo, hi = edges[order, 0], edges[order, 1]
        if abs(lo[0]) > 1e-12 or abs(hi[-1] - 1) > 1e-12 or not np.allclose(lo[1:], hi[:-1]):
            raise GMapError(f"the atlas intervals of age class {c} must be disjoint and cover [0, 1)")
        members = classes == c
        out[members] = order[np.searchsorted(hi, u[members], side="right").clip(0, len(hi) - 1)]
    return out


def to_polydata(lichen: Lichen, mesh: TriMesh, lift: float = 0.0) -> pv.PolyData:
    """The particles as flat discs of radius r on the surface (pyvista), with ``cluster``/``age``."""
    import pyvista as pv

    normals = mesh.normals[lichen.triangle]
    cloud = pv.PolyData(lichen.position + lift * normals)
    cloud.point_data["normal"] = normals
    cloud.point_data["cluster"] = lichen.cluster
    cloud.point_data["age"] = lichen.age
    disc = pv.Disc(inner=0.0, outer=lichen.r, c_res=10, normal=(1, 0, 0))  # glyphs turn their x axis to the normal
    return cloud.glyph(geom=disc, orient="normal", scale=False)
