"""Derive a 3Gmap L-system (a parsed ``.g3l`` grammar) into a 3-G-map.

Step semantics (spec decision 1, *rule-major*): a step is one half-year,
spring on even steps, summer on odd ones.  Within a step each rule, in file
order, is applied to *every* volume that matches it -- the predecessor label
as it stands when the rule's turn comes (a relabel by an earlier rule counts),
the condition, the stochastic choice -- among the volumes that existed when
the step began: volumes made during a step are rewritten from the next step
on.  Every matching rule fires (the same predecessor may head several
rules), except within a stochastic group where a volume picks one.  An add
applies only to free faces (the thesis's self-limiting guard); a join only
to a free face that shares an edge with a free face of the named context.

Geometry is hierarchical: a new volume's frame comes from its support face
on the parent -- origin at the face's centre, heading along the face's
outward normal, ``L`` turned so the prism's corner 0 faces the support
face's corner 0 -- then turned by the volume's three angles; ``(H, L, W)``
are its sizes.  These frames are stored per volume (``origin``, ``frame``,
``size``) and a volume's *default corners* follow from them alone, so
:meth:`G3LDerivation.embed` (default corners, then the kernel's per-vertex
average, spec decision 3) gives the same positions whether it runs after
every step or once at the end.

Provenance: every volume records the rule that made it (``rule``, -1 for the
axiom), the step (``born``), its parent and a *key* -- a hash of its parent's
key, the rule, the face and the step -- that does not depend on volume ids.
Random draws of a volume (``alea``, stochastic choices) are seeded by
``(seed of its branch, key, step, rule)``, so :meth:`G3LDerivation.regrow`
can re-derive one branch with a new seed and leave every other volume as it
was.

>>> from ramure.gmap.lsystem.g3l import parse_g3l
>>> d = G3LSystem(parse_g3l("axiom: A(4)\\n(p1) A -> A[A]_E\\n")).derive(3)
>>> d.gm.n_volumes, d.gm.n_darts, d.gm.euler_characteristic()
(4, 192, 1)
"""

from __future__ import annotations

import math
import os
import re
import time
from collections.abc import Mapping
from typing import Any, SupportsInt

import numpy as np
from numpy.typing import ArrayLike

from ramure.errors import DerivationError, GrammarError
from ramure.gmap.kernel import frames as _frames
from ramure.gmap.lsystem import operators as _ops
from ramure.gmap.kernel import prism as _prism
from ramure.gmap.kernel.errors import GMapError, ValueRefused
from ramure.gmap.lsystem.g3l import PARAM_DEFAULTS, Grammar, load_g3l, parse_g3l
from ramure.gmap.kernel.map3 import GMap3

#: Most darts a derivation may make (about 450 bytes each).
MAX_DARTS = 8_000_000
#: Highest prism order a volume may have (12 darts per side).
MAX_ORDER = 4096
PRISM, WEDGE = 0, 1
_MASK = (1 << 63) - 1


def mix(*values: SupportsInt) -> int:
    """A 63-bit hash of integers (splitmix64 steps); stable across runs and platforms.

    >>> mix(1, 2) == mix(1, 2), mix(1, 2) == mix(2, 1)
    (True, False)
    """
    h = 0x9E3779B97F4A7C15
    for v in values:
        h = (h ^ (int(v) & 0xFFFFFFFFFFFFFFFF)) * 0xBF58476D1CE4E5B9 & 0xFFFFFFFFFFFFFFFF
        h ^= h >> 31
        h = (h * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
        h ^= h >> 29
    return h & _MASK


def wedge_corners(origin: ArrayLike, frame: ArrayLike, size: ArrayLike) -> np.ndarray:
    """Default corners of wedges (relabelled 3-prisms with a quad base; spec decision 2).

    Returned in the 3-prism's corner order ``b0, b1, b2, t0, t1, t2``: the
    quad base ``O`` walks ``b1 t1 t0 b0`` (counter-clockwise about H, like a
    prism's O); the apex edge ``b2 t2`` stands ``H`` above base corners 0 and 1.
    """
    sq = _prism.corners(4, origin, frame, size)[:, :4]
    rise = np.asarray(size, float).reshape(-1, 3)[:, :1] * np.asarray(frame, float).reshape(-1, 3, 3)[:, 0]
    return np.stack([sq[:, 3], sq[:, 0], sq[:, 0] + rise, sq[:, 2], sq[:, 1], sq[:, 1] + rise], axis=1)


#: wedge face relabelling: 3-prism face code -> wedge face code (O quad base, C1 quad, C2 tri, E quad, C4 tri)
_WEDGE_FACES = {2: 0, 3: 2, 1: 3, 4: 1, 0: 5}


def add_wedges(gm: GMap3, count: int, **volume_values: Any) -> np.ndarray:
    """``count`` free wedges (36 darts each) through the kernel's 3-prism, faces relabelled.

    Returns the first dart of each; the O face's forward dart at corner 0 is
    ``first + 14`` and its backward dart there ``first + 13``.
    """
    first = gm.add_prisms(3, count, **volume_values)
    t = _prism.template(3)
    local = first[:, None] + np.arange(t.size)[None, :]
    data = gm.dart_data
    face = t.face.copy()
    new_face = np.array([_WEDGE_FACES[int(c)] for c in face], np.int16)
    data["face"][local] = new_face[None, :]
    base = t.face == 2  # 3-prism C1 becomes O, corner 0 at b1
    fc = t.fcorner.copy()
    fc[base] = (fc[base] - 1) % 4
    data["fcorner"][local] = fc[None, :]
    return first


class _Draws:
    """The random streams of ``alea``, ``uniform`` and ``normal``: one seeded generator per volume.

    A draw for ``n`` volumes takes the next number of each volume's stream, so evaluating
    volumes together gives the same values as evaluating them one at a time.
    """

    def __init__(self, seed_of: Any, count: int) -> None:
        self.seed_of = seed_of
        self.rngs: list[Any] = [None] * count
        self.idx = np.arange(count)

    @classmethod
    def seeded(cls, seeds: list) -> _Draws:
        return cls(lambda i: seeds[i], len(seeds))

    def take(self, idx: Any) -> _Draws:
        """The streams of volumes ``idx`` (shared: drawing here advances them here too)."""
        out = _Draws.__new__(_Draws)
        out.seed_of, out.rngs, out.idx = self.seed_of, self.rngs, self.idx[idx]
        return out

    def _next(self, draw: str) -> np.ndarray:
        out = np.empty(len(self.idx))
        for k, i in enumerate(self.idx.tolist()):  # one step per volume that draws
            rng = self.rngs[i]
            if rng is None:
                rng = self.rngs[i] = np.random.default_rng(self.seed_of(i))
            out[k] = getattr(rng, draw)()
        return out

    def uniform(self, low: Any, high: Any, n: int) -> np.ndarray:
        return low + (high - low) * self._next("random")

    def normal(self, mean: Any, sd: Any, n: int) -> np.ndarray:
        if np.any(np.asarray(sd) < 0):
            raise ValueError("normal() needs a standard deviation >= 0")
        return mean + sd * self._next("standard_normal")


class _Scope:
    """Values an expression reads for ``n`` volumes: parameters ``V``, constants and built-ins ``C``, draws ``R``."""

    def __init__(self, V: dict, C: dict, R: _Draws, n: int) -> None:
        self.V, self.C, self.R, self.n = V, C, R, n

    def take(self, idx: Any) -> _Scope:
        if len(idx) == self.n:
            return self
        pick = np.asarray(idx, np.int64)
        C = {k: v[pick] if isinstance(v, np.ndarray) else v for k, v in self.C.items()}
        return _Scope({k: v[pick] for k, v in self.V.items()}, C, self.R.take(pick), len(pick))


def _finite_or_refuse(values: np.ndarray, what: str) -> None:
    """Refuse a derivation whose sizes overflowed the geometry (a size near 1e308, say)."""
    bad = ~np.isfinite(values.reshape(len(values), -1)).all(axis=1)
    if bad.any():
        raise ValueRefused(
            f"the grammar's sizes overflow: {int(bad.sum())} of {len(values)} {what} are not finite numbers; use smaller sizes"
        )


class G3LSystem:
    """A grammar ready to derive: ``G3LSystem.from_file("wood/spiral").derive(6)``."""

    def __init__(self, grammar: Grammar) -> None:
        self.grammar = grammar

    @classmethod
    def from_file(cls, path: str | os.PathLike) -> G3LSystem:
        return cls(load_g3l(path))

    @classmethod
    def from_text(cls, text: str, filename: str | None = None) -> G3LSystem:
        return cls(parse_g3l(text, filename))

    def derive(
        self,
        steps: int | None = None,
        seed: int = 0,
        embed_every_step: bool = False,
        check_every_step: bool = False,
        overrides: Mapping[int, int] | None = None,
        max_darts: int = MAX_DARTS,
    ) -> G3LDerivation:
        """Run ``steps`` half-year steps (default the grammar's ``#steps``, else 1).

        ``overrides`` maps a volume key to a seed for the branch it heads
        (see :meth:`G3LDerivation.regrow`).  With ``check_every_step``, a step
        that leaves the map invalid or with chi != 1 or boundary chi != 2
        raises :class:`GMapError`.
        """
        steps = self.grammar.steps if steps is None else steps
        steps = 1 if steps is None else int(steps)
        if steps < 0:
            raise ValueRefused(f"steps must be >= 0, got {steps}")
        d = G3LDerivation(self.grammar, int(seed), dict(overrides or {}), max_darts)
        t0 = time.perf_counter()
        for _ in range(steps):
            with np.errstate(over="ignore", invalid="ignore"):
                d.step()
            _finite_or_refuse(d.gm.volume_data["origin"], "volume origins")
            if embed_every_step:
                d.embed()
            if check_every_step:
                d.check_topology()
        with np.errstate(over="ignore", invalid="ignore"):  # huge sizes: refused below, not warned about
            _finite_or_refuse(d.embed(), "points")
        d.seconds = time.perf_counter() - t0
        return d


class G3LDerivation:
    """The growing map and its bookkeeping; ``gm`` is the :class:`GMap3`."""

    def __init__(self, grammar: Grammar, seed: int, overrides: dict[int, int], max_darts: int) -> None:
        self.grammar = grammar
        self.seed = seed
        self.overrides = overrides
        self.max_darts = max_darts
        self.stage = 0
        self.seconds = 0.0
        self.gm = gm = GMap3()
        for name, dtype, shape in (
            ("params", np.float64, (7,)),
            ("born", np.int32, ()),
            ("rule", np.int16, ()),
            ("key", np.int64, ()),
            ("vseed", np.int64, ()),
            ("shape", np.int8, ()),
        ):
            gm.add_volume_data(name, dtype, shape, 0)
        self.corner = np.zeros(0, np.int16)  # template corner of each dart (-1: made by a split)
        self._axiom()

    # ------------------------------------------------------------------ bookkeeping
    def _scope(self, names, vols=None, draws=None):
        """What the expressions of a rule read for volumes ``vols`` (``None``: the axiom), all at once.

        ``names`` are the predecessor's parameter names, bound positionally to each volume's
        parameters (``O`` rounded to a whole number); ``draws`` shares one set of random
        streams between scopes (default: fresh streams, seeded per volume and step).
        """
        vd = self.gm.volume_data
        C = dict(self.grammar.constants)
        C.update(stage=float(self.stage), step=float(self.stage), season=float(self.stage % 2))
        C.update(spring=0.0, summer=1.0, pi=math.pi)
        if vols is None:
            C.update(age=0.0, order=1.0)
            seeds = _Draws.seeded([[self.seed & _MASK, -7 & _MASK, self.stage]])
            return _Scope({}, C, draws or seeds, 1)
        vols = np.asarray(vols, np.int64)
        p = vd["params"][vols]
        V = {name: np.round(p[:, i]) if name == "O" else p[:, i] for i, name in enumerate(names[: p.shape[1]])}
        C.update(age=(self.stage - vd["born"][vols]).astype(float), order=vd["order"][vols].astype(float))
        return _Scope(V, C, draws or self._draws(vols, -7), len(vols))

    def _draws(self, vols, rule):
        """One seeded random stream per volume (the same seeds as :meth:`_rng`), each made on first use."""
        vd = self.gm.volume_data
        vseed, key = vd["vseed"][vols].tolist(), vd["key"][vols].tolist()
        return _Draws(lambda i: [vseed[i] & _MASK, key[i] & _MASK, self.stage, rule & _MASK], len(vseed))

    def _rng(self, v, rule):
        vd = self.gm.volume_data
        return np.random.default_rng([int(vd["vseed"][v]) & _MASK, int(vd["key"][v]) & _MASK, self.stage, rule & _MASK])

    def _error(self, message, expr_or_rule):
        line = getattr(expr_or_rule, "line", None)
        col = getattr(expr_or_rule, "column", 1)
        src = self.grammar.lines[line - 1] if line and line <= len(self.grammar.lines) else None
        return DerivationError(message, line, col, src, self.grammar.filename)

    def _eval(self, expr, scope):
        """``expr`` for every volume of ``scope``: a float array; overflow, 0/0 or x/0 is a DerivationError."""
        try:
            with np.errstate(over="raise", divide="raise", invalid="raise"):
                return expr(scope.V, scope.C, scope.R, scope.n)
        except GrammarError:
            raise
        except (ArithmeticError, ValueError) as err:  # user arithmetic: reported with line and caret
            raise self._error(f"cannot evaluate {expr.text!r} at step {self.stage}: {err}", expr) from None

    def _params(self, call, scope):
        """A Call's parameters for every volume of ``scope``, (n, 7): its arguments, else the symbol's template, else defaults."""
        out = np.tile(np.array(PARAM_DEFAULTS), (scope.n, 1))
        template = self.grammar.templates.get(call.symbol)
        for args in (template.args if template is not None else [], call.args):
            for i, a in enumerate(args):
                if a is not None:
                    out[:, i] = self._eval(a, scope)
        first = call.args[0] if call.args and call.args[0] is not None else None
        order = np.round(out[:, 0])
        if not (order >= 3).all():
            raise self._error(f"prism order must be at least 3, got {order[order < 3][0]:g} for {call.symbol}", first)
        if not (order <= MAX_ORDER).all():
            raise self._error(f"prism order must be at most {MAX_ORDER}, got {order.max():g} for {call.symbol}", first)
        return out

    def _axiom(self) -> None:
        ax = self.grammar.axiom
        p = self._params(ax, self._scope(()))[0]
        self._make(
            1,
            int(p[0]),
            label=ax.symbol,
            params=p[None],
            origin=np.zeros((1, 3)),
            frame=np.eye(3)[[2, 0, 1]][None],
            size=p[None, 4:7],
            parent=[-1],
            rule=[-1],
            key=[1],
            vseed=[self.seed],
            order=[1],
            parent_face=[-2],
        )

    def _sync_corner(self) -> None:
        """Darts made by the kernel (edge splits while sewing) have no template corner."""
        grow = self.gm.n_darts - len(self.corner)
        if grow > 0:
            self.corner = np.concatenate([self.corner, np.full(grow, -1, np.int16)])

    def _make(self, count, n, label, params, origin, frame, size, parent, rule, key, vseed, **extra):
        gm = self.gm
        values = dict(
            label=label, params=params, parent=parent, rule=rule, key=key, vseed=vseed, born=self.stage, stage=self.stage
        )
        values.update(extra)
        values.update(origins=origin, frames=frame, sizes=size)
        if n == 3:
            first = add_wedges(gm, count, **values)
            corner = _prism.template(3).corner
            gm.volume_data["shape"][gm.n_volumes - count :] = WEDGE
        else:
            first = gm.add_prisms(n, count, **values)
            corner = _prism.template(n).corner
        grow = gm.n_darts - len(self.corner)
        self.corner = np.concatenate([self.corner, np.full(grow, -1, np.int16)])
        local = first[:, None] + np.arange(len(corner))[None, :]
        self.corner[local] = corner[None, :]
        return first

    # ------------------------------------------------------------------ steps
    def step(self) -> None:
        """Apply every rule once (rule-major), then advance the half-year counter."""
        n_start = self.gm.n_volumes
        choice: dict[tuple[int, int], int] = {}  # (stochastic group, volume) -> chosen rule index
        for rule in self.grammar.rules:
            labels = self.gm.volume_data["label"][:n_start]
            vols = np.flatnonzero(labels == rule.pred)
            if vols.size == 0:
                continue
            chosen = self._firing(rule, vols, choice)
            if not chosen.size:
                continue
            if rule.op == "add":
                self._apply_add(rule, chosen)
            elif rule.op == "split":
                self._apply_split(rule, chosen.tolist())
            else:
                self._apply_join(rule, chosen.tolist())
        self.stage += 1

    def _firing(self, rule, vols, choice):
        """The volumes among ``vols`` that ``rule`` rewrites: its stochastic pick, context and condition."""
        keep = np.ones(len(vols), bool)
        if rule.group >= 0:
            todo = [v for v in vols.tolist() if (rule.group, v) not in choice]
            if todo:
                for v, pick in zip(todo, self._pick(rule.group, np.array(todo, np.int64))):
                    choice[(rule.group, v)] = pick
            keep = np.array([choice[(rule.group, v)] == rule.index for v in vols.tolist()])
        if rule.condition is None:
            return vols[keep]
        if rule.context:
            keep[keep] = self._context_ok(rule, vols[keep])
        idx = np.flatnonzero(keep)
        if idx.size:
            keep[idx] = self._eval(rule.condition, self._scope(rule.pred_params, vols[idx])) != 0
        return vols[keep]

    def _pick(self, group, vols):
        """The rule index each volume of ``vols`` picks in a stochastic group (-1: none)."""
        rules = [r for r in self.grammar.rules if r.group == group]
        u = np.array([self._rng(v, 1000 + group).random() for v in vols.tolist()])
        draws = self._draws(vols, -7)  # one stream per volume for the whole group
        probs = np.stack([self._eval(r.probability, self._scope(r.pred_params, vols, draws)) for r in rules])
        for r, prob in zip(rules, probs):
            bad = prob[~((prob >= 0) & (prob <= 1))]
            if bad.size:
                raise self._error(f"a probability must be in [0, 1], got {bad[0]:g}", r.probability)
        total = np.cumsum(probs, axis=0)  # the same sums, in the same order, as one volume at a time
        if (total[-1] > 1 + 1e-9).any():
            raise self._error(
                f"probabilities of the rules for {rules[0].pred} add up to {total[-1].max():g} > 1", rules[0].probability
            )
        hit = u[None, :] < total
        first = np.argmax(hit, axis=0)
        return np.where(hit.any(axis=0), np.array([r.index for r in rules])[first], -1).tolist()

    def _context_ok(self, rule, vols: np.ndarray) -> np.ndarray:
        """Which of ``vols`` meet every context of ``rule`` (all volumes at once)."""
        ok = np.ones(len(vols), bool)
        for face, sym, other, col in rule.context:
            ok[ok] = self._adjacent(vols[ok], face, sym, other, rule, col)
        return ok

    def _face_codes(self, vols, label, rule, column):
        """:meth:`_face_code` for many volumes: checked once per kind of volume (order, shape), in
        the volumes' order, so a refusal names the first volume that lacks the face."""
        vd = self.gm.volume_data
        kinds = vd["degree"][vols].astype(np.int64) * 2 + vd["shape"][vols]
        _, first = np.unique(kinds, return_index=True)
        for i in np.sort(first).tolist():
            self._face_code(int(vols[i]), label, rule, column)

    def _face_code(self, v, label, rule, column):
        gm = self.gm
        code = _prism.face_label_code(label) if re.fullmatch(r"O|E|C[1-9]\d*", label) else -1
        n = int(gm.volume_data["degree"][v])
        shape = int(gm.volume_data["shape"][v])
        valid = {0, 1} | ({2, 3, 5} if shape == WEDGE else set(range(2, n + 2)))
        if code not in valid:
            kind = "wedge" if shape == WEDGE else f"prism of order {n}"
            src = self.grammar.lines[rule.line - 1]
            raise DerivationError(
                f"rule {rule.name}: volume {v} ({gm.volume_data['label'][v]}) is a {kind} and has no face {label}",
                rule.line,
                column,
                src,
                self.grammar.filename,
            )
        return code

    def _adjacent(self, vols, face, sym, other, rule, col):
        """Per volume of ``vols``: its free face ``face`` shares an edge with face ``other`` of a
        volume labelled ``sym`` (the rule's context)."""
        gm = self.gm
        out = np.zeros(len(vols), bool)
        if not len(vols):
            return out
        free, walk, nb = self._free_face_neighbours(vols, face, rule, col)
        there = np.maximum(nb, 0)
        code = _prism.face_label_code(other)
        hit = (walk >= 0) & (gm.volume_data["label"][gm.dart_volume[there]] == sym) & (gm.dart_data["face"][there] == code)
        out[free] = hit.any(axis=1)
        return out

    def _free_face_neighbours(self, vols, face, rule, col):
        """For ``vols``: which have a free face ``face`` (bool per volume), then, one row per such
        volume, the face's darts (``-1`` padded) and each dart's boundary neighbour (``-1`` there)."""
        gm = self.gm
        self._face_codes(vols, face, rule, col)
        starts = _ops.face_starts(gm, vols, face)
        free = starts >= 0
        free[free] = _ops.face_is_free(gm, starts[free])
        if not free.any():
            empty = np.zeros((0, 0), np.int64)
            return free, empty, empty
        walk, _ = gm.face_walk(starts[free])
        mine = walk >= 0
        nb = np.full(walk.shape, -1, np.int64)
        nb[mine] = _ops.boundary_neighbour(gm, walk[mine])
        return free, walk, nb

    # ------------------------------------------------------------------ operators
    def _faces_of(self, rule, spec, vols, scope):
        """The face labels ``spec`` names on each volume of ``vols``: a list of lists."""
        vd = self.gm.volume_data
        degree, shape = vd["degree"][vols].tolist(), vd["shape"][vols].tolist()
        sides = [[1, 2, 4] if s == WEDGE else list(range(1, n + 1)) for n, s in zip(degree, shape)]
        if spec.kind in ("O", "E"):
            return [[spec.kind] for _ in vols]
        if spec.kind == "Call":
            return [[f"C{k}" for k in ks] for ks in sides]
        if spec.kind in ("C", "Cexcept"):
            index = np.clip(np.round(self._eval(spec.index, scope)), -(2**31), 2**31).astype(np.int64).tolist()
            if spec.kind == "Cexcept":
                return [[f"C{j}" for j in ks if j != k] for ks, k in zip(sides, index)]
            if spec.text[1:].isdigit():
                for v, k in zip(vols.tolist(), index):
                    self._face_code(v, f"C{k}", rule, spec.column)
                return [[f"C{k}"] for k in index]
            return [[f"C{(k - 1) % n + 1}"] for k, n in zip(index, degree)]
        out: list[list[str]] = [[] for _ in vols]
        for sub in spec.index:
            for mine, more in zip(out, self._faces_of(rule, sub, vols, scope)):
                mine.extend(more)
        return out

    def _apply_add(self, rule, vols) -> None:
        """Relabel ``vols`` and add the bracketed volumes on their free faces.

        Expressions are evaluated for all volumes at once, in the order a volume reads
        them (brackets and their faces, then the head), so each volume's random stream
        gives the same draws as evaluating one volume at a time.
        """
        gm = self.gm
        scope = self._scope(rule.pred_params, vols)
        mine: list[list] = [[] for _ in vols]  # each volume's requests, in order
        for slot, (call, spec) in enumerate(rule.brackets):
            faces = self._faces_of(rule, spec, vols, scope)
            template = self.grammar.templates.get(call.symbol)
            random = any(a is not None and a.random for a in call.args + (template.args if template else []))
            params = np.zeros((len(vols), 7)) if random else self._params(call, scope)
            for j in range(max(map(len, faces), default=0)):
                idx = [i for i, f in enumerate(faces) if len(f) > j]
                if random:  # one draw per face, as the volume reads them
                    params = np.zeros((len(vols), 7))
                    params[idx] = self._params(call, scope.take(idx))
                for i in idx:
                    self._face_code(int(vols[i]), faces[i][j], rule, spec.column)
                    mine[i].append((int(vols[i]), faces[i][j], call.symbol, params[i], slot))
        if rule.head is not None:
            gm.volume_data["label"][vols] = rule.head.symbol
            if rule.head.args:
                gm.volume_data["params"][vols] = self._params(rule.head, scope)
        requests = [r for reqs in mine for r in reqs]
        if requests:
            self._add_children(rule, requests)

    def _add_children(self, rule, requests):
        gm = self.gm
        vols = np.array([r[0] for r in requests], np.int64)
        starts = self._starts(vols, [r[1] for r in requests])
        ok = starts >= 0
        ok[ok] = _ops.face_is_free(gm, starts[ok])
        requests = [r for r, keep in zip(requests, ok) if keep]
        starts, vols = starts[ok], vols[ok]
        if not requests:
            return
        params = np.stack([r[3] for r in requests])
        orders = params[:, 0].round().astype(int)
        extra = int(np.sum(np.where(orders == 3, 36, 12 * orders)))
        if gm.n_darts + extra > self.max_darts:
            raise ValueRefused(
                f"step {self.stage}: the map would exceed {self.max_darts:,} darts "
                f"(rule {rule.name} adds {len(requests)} volumes); derive fewer steps"
            )
        origin, frame, forward, walk_corner0 = self._support_frames(starts, vols, orders)
        frame = _frames.rotate(frame, params[:, 1], params[:, 2], params[:, 3])
        vd = gm.volume_data
        for order in np.unique(orders):  # one batch per prism order
            idx = np.flatnonzero(orders == order)
            codes = [_prism.face_label_code(requests[i][1]) for i in idx]
            keys = [mix(int(vd["key"][vols[i]]), rule.index, c, requests[i][4], self.stage) for i, c in zip(idx, codes)]
            vseed = [self.overrides.get(k, int(vd["vseed"][vols[i]])) for k, i in zip(keys, idx)]
            side = np.array([c >= 2 for c in codes])
            first = self._make(
                len(idx),
                int(order),
                label=np.array([requests[i][2] for i in idx]),
                params=params[idx],
                origin=origin[idx],
                frame=frame[idx],
                size=params[idx, 4:7],
                parent=vols[idx],
                rule=rule.index,
                key=keys,
                vseed=vseed,
                order=vd["order"][vols[idx]] + side,
                parent_face=codes,
            )
            if order == 3:
                new_o = np.where(forward[idx], first + 14, first + 13)
            else:
                new_o = np.where(forward[idx], first, first + 2 * order - 1)
            _ops.sew_pairs(gm, starts[idx], new_o)
            self._sync_corner()

    def _starts(self, vols: np.ndarray, labels: list[str]) -> np.ndarray:
        """:func:`~ramure.gmap.lsystem.operators.face_starts` of face ``labels[i]`` of ``vols[i]``:
        one pass over the map per face label, not per request."""
        out = np.full(len(vols), -1, np.int64)
        names = np.array(labels, dtype=object)
        for label in dict.fromkeys(labels):
            idx = np.flatnonzero(names == label)
            unique, back = np.unique(vols[idx], return_inverse=True)
            out[idx] = _ops.face_starts(self.gm, unique, label)[back]
        return out

    def default_corners(self, volumes: ArrayLike | None = None) -> list[np.ndarray]:
        """Default corners of ``volumes`` from their stored frames: a list of (2n, 3) arrays."""
        vd = self.gm.volume_data
        volumes = np.arange(self.gm.n_volumes) if volumes is None else np.asarray(volumes, np.int64)
        out: list[Any] = [None] * len(volumes)  # every slot is filled below
        deg, shape = vd["degree"][volumes], vd["shape"][volumes]
        for key in set(zip(deg.tolist(), shape.tolist())):
            idx = np.flatnonzero((deg == key[0]) & (shape == key[1]))
            v = volumes[idx]
            if key[1] == WEDGE:
                c = wedge_corners(vd["origin"][v], vd["frame"][v], vd["size"][v])
            else:
                c = _prism.corners(key[0], vd["origin"][v], vd["frame"][v], vd["size"][v])
            for i, arr in zip(idx, c):
                out[i] = arr
        return out

    def _support_frames(self, starts, vols, orders):
        """Frames on the support faces: origin, rows (H, L, U), forward pairing, corner 0.

        All support faces of one length at once: a face's corners are its parent's default
        corners where the dart has a template corner, else the map's corners.
        """
        gm = self.gm
        walk, length = gm.face_walk(starts)
        parents, parent_of = np.unique(vols, return_inverse=True)
        corners = self.default_corners(parents)
        flat = np.concatenate(corners)
        offset = np.concatenate([[0], np.cumsum([len(c) for c in corners])[:-1]])
        middle = np.array([c.mean(axis=0) for c in corners])
        k = len(starts)
        origin, frame = np.zeros((k, 3)), np.zeros((k, 3, 3))
        forward = np.ones(k, bool)
        c0 = np.zeros((k, 3))
        for size in np.unique(length).tolist():
            idx = np.flatnonzero(length == size)
            w = walk[idx, :size:2]
            cid = self.corner[w].astype(np.int64)
            mine = flat[offset[parent_of[idx]][:, None] + np.maximum(cid, 0)]
            pts = np.where(cid[..., None] >= 0, mine, gm.corners[w])
            centre = pts.mean(axis=1)
            newell = np.cross(pts, np.roll(pts, -1, axis=1)).sum(axis=1)
            outward = centre - middle[parent_of[idx]]
            sign = np.where(np.einsum("ij,ij->i", newell, outward) >= 0, 1.0, -1.0)
            h = sign[:, None] * newell / np.maximum(np.linalg.norm(newell, axis=1), 1e-300)[:, None]
            u0 = pts[:, 0] - centre
            u0 -= np.einsum("ij,ij->i", u0, h)[:, None] * h
            u0 /= np.maximum(np.linalg.norm(u0, axis=1), 1e-300)[:, None]
            n = np.where(orders[idx] == 3, 4, orders[idx]).astype(np.float64)[:, None]
            left = np.cos(np.pi / n) * u0 + np.sin(np.pi / n) * np.cross(h, u0)
            origin[idx], frame[idx] = centre, np.stack([h, left, np.cross(h, left)], axis=1)
            forward[idx] = sign > 0
            c0[idx] = pts[:, 0]
        return origin, frame, forward, c0

    def _apply_split(self, rule, vols) -> None:
        gm = self.gm
        vd = gm.volume_data
        inner, outer = rule.split_parts
        for v in vols:  # one step per split volume
            code_name = rule.split_face
            self._face_code(v, code_name, rule, 1)
            start = _ops.face_starts(gm, [v], code_name)[0]
            opp = {"O": "E", "E": "O"}.get(code_name, code_name)
            new = gm.split_prism(int(v), 0.5, face=int(start), labels=(opp, code_name))
            grow = gm.n_darts - len(self.corner)
            self.corner = np.concatenate([self.corner, np.full(grow, -1, np.int16)])
            self.corner[gm.dart_volume == v] = -1
            self.corner[gm.dart_volume == new] = -1
            vd["label"][v], vd["label"][new] = inner, outer
            vd["shape"][v] = vd["shape"][new] = -1  # manual embedding from now on
            if code_name in ("O", "E"):  # halves along H: children frame on them
                half = 0.5 * vd["size"][v, 0]
                heading = vd["frame"][v, 0]
                vd["size"][v, 0] = vd["size"][new, 0] = half
                if code_name == "O":
                    vd["origin"][new] = vd["origin"][v] + half * heading
                else:
                    vd["origin"][v] = vd["origin"][v] + half * heading
            vd["rule"][new], vd["born"][new], vd["parent"][new] = rule.index, self.stage, v
            vd["key"][new] = mix(int(vd["key"][v]), rule.index, self.stage, 99)

    def _apply_join(self, rule, vols) -> None:
        gm = self.gm
        face_a, sym_b, face_b = rule.join
        code_b = _prism.face_label_code(face_b)
        a_list, b_list, used = [], [], set()
        code_a = _prism.face_label_code(face_a)
        for v, mine, nb in self._join_candidates(rule, np.asarray(vols, np.int64), face_a, sym_b, code_b):
            for a, b in zip(mine.tolist(), nb.tolist()):  # the first free partner face not yet taken
                fb = (int(gm.dart_volume[b]), code_b)
                if fb in used or (v, code_a) in used:
                    continue
                used.add(fb)
                used.add((v, code_a))
                a_list.append(a)
                b_list.append(b)
                break
        if a_list:  # the kernel's identify: start darts and sense from the shared edge
            gm.identify(np.array(a_list, np.int64), np.array(b_list, np.int64))
        self._sync_corner()

    def _join_candidates(self, rule, vols, face_a, sym_b, code_b):
        """Per volume whose free face ``face_a`` touches a free face ``code_b`` of a ``sym_b``
        volume: ``(volume, its darts, their partners)`` in the face walk's order, computed for
        all volumes at once (the map does not change until the joins are made together)."""
        gm, vd = self.gm, self.gm.volume_data
        if not len(vols):
            return []
        free, walk, nb = self._free_face_neighbours(vols, face_a, rule, 1)
        there = np.maximum(nb, 0)
        owner = vols[free][:, None]
        hit = (walk >= 0) & (vd["label"][gm.dart_volume[there]] == sym_b) & (gm.dart_data["face"][there] == code_b)
        hit &= gm.dart_volume[there] != owner
        hit[hit] = _ops.face_is_free(gm, there[hit])
        return [(int(v), walk[i][hit[i]], nb[i][hit[i]]) for i, v in enumerate(vols[free].tolist()) if hit[i].any()]

    # ------------------------------------------------------------------ results
    def embed(self) -> np.ndarray:
        """Default corners on every dart, then the kernel's per-vertex average; returns positions."""
        gm = self.gm
        if not gm.n_volumes:
            return np.zeros((0, 3))
        self._sync_corner()
        corners = self.default_corners()
        ok = self.corner >= 0
        vol = gm.dart_volume
        lengths = np.array([len(c) for c in corners])
        offset = np.concatenate([[0], np.cumsum(lengths)[:-1]])
        flat = np.concatenate(corners)
        manual = gm.volume_data["shape"][vol] < 0
        use = ok & ~manual
        gm.corners[use] = flat[offset[vol[use]] + self.corner[use]]  # embed reads corners, writes points
        return gm.embed()

    def check_topology(self) -> None:
        """Raise :class:`GMapError` unless valid, chi = 1 and boundary chi = 2."""
        from ramure.gmap.kernel.topology import assert_solid

        try:
            assert_solid(self.gm)
        except GMapError as err:
            raise GMapError(f"after step {self.stage}: {err}") from None

    def provenance(self, volume: int) -> list[tuple[str, int]]:
        """``[(rule name, step), ...]`` from ``volume`` back to the axiom."""
        vd = self.gm.volume_data
        out = []
        v = int(volume)
        while v >= 0:
            r = int(vd["rule"][v])
            out.append(("axiom" if r < 0 else self.grammar.rules[r].name, int(vd["born"][v])))
            v = int(vd["parent"][v])
        return out

    def branch(self, volume: int) -> np.ndarray:
        """Volume ids of the branch headed by ``volume``: it and all its descendants."""
        parent = self.gm.volume_data["parent"].astype(np.int64)
        inside = np.zeros(len(parent), bool)
        inside[int(volume)] = True
        for _ in range(len(parent)):
            grow = ~inside & (parent >= 0) & inside[np.maximum(parent, 0)]
            if not grow.any():
                break
            inside |= grow
        return np.flatnonzero(inside)

    def regrow(self, volume: int, seed: int, steps: int | None = None) -> G3LDerivation:
        """Re-derive with the branch headed by ``volume`` reseeded; a new :class:`G3LDerivation`.

        Volumes outside the branch keep their keys and their draws, hence
        their parameters; only the branch (and, through shared vertices, its
        alpha3 neighbours' positions) can change.
        """
        key = int(self.gm.volume_data["key"][int(volume)])
        overrides = {**self.overrides, key: int(seed)}
        return G3LSystem(self.grammar).derive(
            self.stage if steps is None else steps, self.seed, overrides=overrides, max_darts=self.max_darts
        )
