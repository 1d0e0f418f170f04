"""L-Py ``.lpy`` models: **opening one runs its Python code**, as L-Py does.

An ``.lpy`` file is a Python program with L-system sections.  Ramure translates the sections
into Python (:mod:`ramure.lsys.readers.lpy_translate`: rules become functions with ``produce`` and
``nproduce``) and runs the result with Python's ``exec``, in a namespace holding ``math``'s
names, Ramure's small PlantGL (:mod:`ramure.lsys.readers.lpy_plantgl`, also what ``import
openalea.plantgl.all`` gives) and L-Py's ``useGroup``, ``getIterationNb``, ``Stop``,
``extern`` and ``context``.  The code can do anything a script can: open only files you would
run (docs/security.md).  The initialisation section (``__initialiseContext__``: materials,
``__scalars__``, curves, ``__parameterset__``) runs first, then the file.

Derivation follows L-Py: at each step ``StartEach``, then every module in string order tries
the rules of its symbol in file order (group 0 and the group ``useGroup`` chose); a rule whose
function returns None does not apply; then the decomposition rules (``maximum depth``, default
1) and ``EndEach``; ``Start`` and ``End`` run once.  Contexts skip whole branches and the
``ignore:`` (or non-``consider:``) symbols.  Every rule application is recorded in Ramure's
history tree (the produced modules are the children of the module they rewrote), so a model
can be selected and regrown (:func:`ramure.lsys.regenerate`).  A regrowth reruns the rules
with the namespace as the derivation left it (globals a hook changed keep their last value).
Interpretation rules are applied for drawing only.

Numeric ``extern(...)`` values and ``__scalars__`` are the model's constants (``--set``).
Parameters that are not numbers (vectors, curves) are kept with the history; the tree's
parameter table holds the numbers.  Rule bodies are Python, so a step is a Python loop over
the modules (as in L-Py, which calls Python for each rule too).

>>> text = "Axiom: A(1)\\nderivation length: 2\\nproduction:\\nA(x) :\\n  produce F(x)[+A(x+1)]A(x+1)\\nendlsystem\\n"
>>> LpyLSystem(text).derive().to_string()
'F(1)[+F(2)[+A(3)]A(3)]F(2)[+A(3)]A(3)'
"""

from __future__ import annotations

import builtins
import copy
import inspect
import math
import random
import types
import weakref
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields, is_dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from . import lpy_plantgl
from ..engine.combination import split as split_combination
from ..engine.derive import FILE_READERS, Derivation, LSystem, check_seed
from ..errors import DerivationError, GrammarError
from ..language.grammar import Grammar
from .lpy_translate import LpyError, LpyRule, Translation, translate
from ..history.tree import DerivationTree

if TYPE_CHECKING:
    from ..interpretation.turtle import Skeleton

#: L-Py's long turtle names that are one of Ramure's turtle symbols.
ALIASES = {
    "SetWidth": "_",
    "IncColor": ";",
    "DecColor": ",",
    "SetColor": ";",
    "Left": "+",
    "Right": "-",
    "Up": "^",
    "Down": "&",
    "RollL": "\\",
    "RollR": "/",
    "TurnAround": "|",
    "Sphere": "@O",
    "Elasticity": "@Ts",
}
#: Parameters per module kept in the history tree's number table (all are kept with the history).
TABLE_PARAMS = 8
_INIT_MARKS = ("###### INITIALISATION", "__lpy_code_version__", "def __initialiseContext__")
_MAIN, _INIT = "<lpy>", "<lpy-init>"


@dataclass
class _Runtime:
    """What the translated code calls: the produce buffer, the group, the step, Stop."""

    buffer: list = field(default_factory=list)
    group: int = 0
    iteration: int = 0
    stopped: bool = False
    backward: bool = False

    def produce(self, modules: list) -> list:
        out, self.buffer = self.buffer + modules, []
        return out

    def nproduce(self, modules: list) -> None:
        self.buffer.extend(modules)


@dataclass
class _Record:
    """One history tree's L-Py side: the namespace, the rules and every node's symbol and arguments."""

    ns: dict
    rt: _Runtime
    rules: dict
    syms: list = field(default_factory=list)
    args: list = field(default_factory=list)


class _Ignored(types.SimpleNamespace):
    """Display settings Ramure does not use (the turtle's and the options'): every call is accepted."""

    def __getattr__(self, name: str) -> Callable[..., None]:
        return lambda *args, **kw: None


class _Context:
    """The L-Py turtle context an ``__initialiseContext__`` writes into."""

    def __init__(self, ns: dict, fixed: Mapping[str, Any], materials: dict) -> None:
        self.ns, self.fixed = ns, fixed
        self.turtle = _Ignored(setMaterial=self.set_material)
        self.options = _Ignored()
        self.materials = materials
        self.animation_timestep = 0

    def __setitem__(self, name: str, value: Any) -> None:
        if name not in self.fixed:
            self.ns[name] = value

    def __getitem__(self, name: str) -> Any:
        return self.ns[name]

    def __contains__(self, name: str) -> bool:
        return name in self.ns

    def set_material(self, index: int, material: Any) -> None:
        if isinstance(material, lpy_plantgl.Color3):
            material = lpy_plantgl.Material(material)
        self.materials[int(index)] = material.rgba()


def _shim_module(name: str, names: dict) -> types.ModuleType:
    module = types.ModuleType(name)
    module.__dict__.update(names)

    def missing(attr: str) -> Any:
        if attr.startswith("__"):
            raise AttributeError(attr)
        raise LpyError(f"{name}.{attr} is not in Ramure's small PlantGL/L-Py (see ramure.lsys.readers.lpy_plantgl)")

    module.__getattr__ = missing  # type: ignore[method-assign]  # a module-level __getattr__ (PEP 562)
    return module


def _openalea() -> dict[str, types.ModuleType]:
    pgl = lpy_plantgl.names()
    mods = {n: _shim_module(n, pgl) for n in ("openalea.plantgl.all", "openalea.plantgl.math", "openalea.plantgl.scenegraph")}
    mods["openalea.plantgl"] = _shim_module("openalea.plantgl", {"all": mods["openalea.plantgl.all"]})
    mods["openalea.plantgl"].__dict__.update(math=mods["openalea.plantgl.math"], scenegraph=mods["openalea.plantgl.scenegraph"])
    mods["openalea.lpy"] = _shim_module("openalea.lpy", {})
    mods["openalea"] = _shim_module("openalea", {"plantgl": mods["openalea.plantgl"], "lpy": mods["openalea.lpy"]})
    return mods


def _builtins() -> dict:
    shims = _openalea()

    def lpy_import(name: str, globals: Any = None, locals: Any = None, fromlist: Any = (), level: int = 0) -> Any:
        if name == "openalea" or name.startswith("openalea."):
            if name not in shims:
                raise LpyError(f"the module {name} is not in Ramure's small PlantGL/L-Py")
            return shims[name] if fromlist else shims["openalea"]
        return builtins.__import__(name, globals, locals, fromlist, level)

    return {**builtins.__dict__, "__import__": lpy_import}


class LpyLSystem(LSystem):
    """An L-Py model ready to derive (see the module's docstring: opening one runs its code)."""

    #: The suffix of the reader its text needs: a session of it names it (``Session.save``).
    READER = ".lpy"

    def __init__(self, text: str, filename: str | None = None) -> None:
        main, init = _split_init(text)
        self.translation = translate(main, filename)
        self.filename = filename
        self._code = self._compile_code(self.translation.source, _MAIN, filename)
        self._init = self._compile_code(init, _INIT, filename)
        self._records: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
        self.materials: dict[int, tuple] = {}
        rec = self._run({})
        axiom = rec.ns.get("__axiom__")
        #: the axiom as the file's run gave it (its code may compute it), as text
        self.axiom_text = "".join(_module_text(m) for m in axiom) if isinstance(axiom, list) else ""
        n = int(rec.ns.get("__derivation_length__", 1))
        grammar = Grammar(text=text, constants=self._externs, axiom=[], rules=[], n=n, angle=60.0, step=1.0)
        grammar.filename, grammar.materials = filename, dict(self.materials)
        super().__init__(grammar)
        self.max_params = TABLE_PARAMS

    def _compile_code(self, source: str, name: str, filename: str | None) -> types.CodeType:
        try:
            return compile(source, name, "exec")
        except SyntaxError as exc:
            line = exc.lineno or 1
            if name == _MAIN:
                line = self.translation.origin[min(line, len(self.translation.origin)) - 1]
            raise LpyError(f"Python syntax: {exc.msg}", line, exc.offset, None, filename) from None

    # -- running the file ------------------------------------------------------
    def _run(self, overrides: Mapping[str, Any]) -> _Record:
        """A fresh namespace: the initialisation section, then the file (``overrides`` win)."""
        rt = _Runtime()
        ns: dict[str, Any] = {k: getattr(math, k) for k in dir(math) if not k.startswith("_")}
        ns.update(lpy_plantgl.names())
        externs: dict[str, Any] = {}
        context = _Context(ns, overrides, self.materials)

        def extern(**values: Any) -> None:
            externs.update(values)
            for k, v in values.items():
                ns.setdefault(k, v)

        def stop() -> None:
            rt.stopped = True

        def use_group(g: int) -> None:
            rt.group = int(g)

        ns.update(
            __builtins__=_builtins(),
            __name__="__lpy__",
            __produce__=rt.produce,
            __nproduce__=rt.nproduce,
            __max_depth__={},
            extern=extern,
            useGroup=use_group,
            getGroup=lambda: rt.group,
            getIterationNb=lambda: rt.iteration,
            Stop=stop,
            forward=lambda: setattr(rt, "backward", False),
            backward=lambda: setattr(rt, "backward", True),
            isForward=lambda: not rt.backward,
            frameDisplay=lambda *a: None,
            context=lambda: context,
            execContext=lambda: context,
            isAnimationEnabled=lambda: False,
            ParameterSet=lpy_plantgl.ParameterSet,  # openalea.lpy's, as every .lpy file sees it
        )
        ns.update(overrides)
        self._exec(self._init, ns)
        if callable(ns.get("__initialiseContext__")):
            self._call(ns["__initialiseContext__"], context)
        self._exec(self._code, ns)
        scalars = {s[0]: s[2] for s in ns.get("__scalars__", ()) if isinstance(s, (tuple, list)) and len(s) > 2}
        values = {k: v for k, v in {**scalars, **externs}.items() if _is_number(v)}
        self._externs = {k: float(v) for k, v in values.items()}
        self._ints = getattr(self, "_ints", None) or {k for k, v in values.items() if isinstance(v, (int, np.integer))}
        return _Record(ns, rt, self._rule_table(ns))

    def _like(self, name: str, value: float) -> Any:
        return int(value) if name in self._ints and float(value).is_integer() else value

    def _exec(self, code: types.CodeType, ns: dict) -> None:
        self._call(lambda: exec(code, ns))

    def _call(self, fn: Callable, *args: Any) -> Any:
        """Call the file's code; any error it raises becomes an :class:`LpyError` at the file's line."""
        try:
            return fn(*args)
        except GrammarError as exc:
            if exc.line is None:
                exc.line, exc.filename = _file_line(exc, self.translation), self.filename
                exc.args = (exc.formatted(),)
            raise
        except Exception as exc:
            hint = " (not defined by the file nor by Ramure's L-Py)" if isinstance(exc, NameError) else ""
            message = f"{type(exc).__name__}: {exc}{hint}"
            raise DerivationError(message, _file_line(exc, self.translation), None, None, self.filename) from None

    def _rule_table(self, ns: dict) -> dict:
        table: dict[str, dict[int, list]] = {"production": {}, "decomposition": {}, "interpretation": {}}
        for k, rule in enumerate(self.translation.rules):
            pred, left, right = ([(self.intern(s), a) for s, a in p] for p in (rule.pred, rule.left, rule.right))
            table[rule.section].setdefault(pred[0][0], []).append((k, rule, ns[rule.function], pred, left, right))
        return table

    def intern(self, name: str) -> int:
        """The symbol id of module ``name`` (L-Py's long turtle names are Ramure's symbols)."""
        name = ALIASES.get(name, name)
        sid = self._sym.get(name) if hasattr(self, "_sym") else None
        if sid is None:
            if not hasattr(self, "_sym"):
                self.symbols, self._sym = [], {}
            sid = self._sym[name] = len(self.symbols)
            self.symbols.append(name)
        return sid

    def __setattr__(self, name: str, value: Any) -> None:
        if name in ("symbols", "_sym") and hasattr(self, name):
            return  # LSystem.__init__ would reset the symbols interned while running the file
        super().__setattr__(name, value)

    def copy(self) -> LpyLSystem:
        """This model with its own constants (the file is not run again: the compiled code is shared)."""
        current = copy.copy(self)
        current.constants = dict(self.grammar.constants)
        return current

    def turtle_arguments(self, tree: DerivationTree, nodes: np.ndarray) -> list[tuple]:
        """The arguments of modules ``nodes`` of ``tree`` as the file gave them (vectors and
        curves too), for the turtle's commands of several parameters."""
        rec = self._records.get(tree)
        if rec is None:
            return [tuple(float(v) for v in tree.params[n, : tree.nparams[n]]) for n in nodes.tolist()]
        return [tuple(rec.args[n]) for n in nodes.tolist()]

    def rule_counts(self) -> dict[str, int]:
        """How many rules each of the file's sections holds (``production:``, ``decomposition:``,
        ``interpretation:``/``homomorphism:``)."""
        counts = {"production": 0, "decomposition": 0, "interpretation": 0}
        for rule in self.translation.rules:
            counts[rule.section] += 1
        return counts

    @property
    def has_context(self) -> bool:
        return any(r.left or r.right for r in self.translation.rules)

    # -- deriving ----------------------------------------------------------------
    def derive(
        self,
        n: int | None = None,
        seed: int | None = None,
        constants: Mapping[str, float] | None = None,
        params: dict | None = None,
        progress: Callable[[int, int], None] | None = None,
    ) -> Derivation:
        """Run the file afresh and derive ``n`` steps (default: its ``derivation length``).

        :attr:`constants` (its numeric ``extern``/``__scalars__`` values, editable) and then
        ``constants`` override the file's values; ``seed`` seeds
        Python's :mod:`random` before ``Start`` (a file that calls ``random.seed`` reseeds it).
        """
        extra, _ = split_combination(params)
        given = {**(constants or {}), **extra}
        unknown = set(given) - set(self.constants)
        if unknown:
            raise GrammarError(
                f"unknown constant(s): {', '.join(sorted(unknown))}; "
                f"the model's externs are {', '.join(self.constants) or 'none'}"
            )
        seed = self.seed if seed is None else check_seed(seed)
        random.seed(seed)
        # self.constants may have been edited (--set); a whole number stays an int where the file wrote one
        overrides = {k: self._like(k, v) for k, v in {**self.constants, **given}.items()}
        rec = self._run(overrides)
        steps = int(rec.ns.get("__derivation_length__", 1)) if n is None else int(n)
        if not 0 <= steps <= self.max_steps:
            raise GrammarError(f"the derivation count must be from 0 to {self.max_steps}, not {steps}")
        tree = DerivationTree(TABLE_PARAMS, capacity=1024)
        self._records[tree] = rec
        string = self._axiom(tree, rec)
        self._answer_queries(tree, rec, string, 0)
        self._hook(rec, "Start")
        done = 0
        for step in range(1, steps + 1):
            if rec.rt.stopped:
                break
            rec.rt.iteration = step - 1
            self._hook(rec, "StartEach")
            first = tree.size
            string = self.rewrite(tree, string, step, np.random.default_rng(seed), {})
            self._answer_queries(tree, rec, string, first)
            self._hook(rec, "EndEach", tree, string)
            done = step
            if progress is not None:
                progress(step, steps)
        self._hook(rec, "End", tree, string)
        tree.leaves = string
        tree.compact_params()
        tree.changed()
        consts = {k: float(v) for k, v in overrides.items()}
        return LpyDerivation(self, tree, n=done, seed=seed, constants=consts, params=params)

    def _axiom(self, tree: DerivationTree, rec: _Record) -> np.ndarray:
        axiom = rec.ns.get("__axiom__")
        if not isinstance(axiom, list):
            raise LpyError("the file has no 'Axiom:'", None, None, None, self.filename)
        builder = _Builder(self, tree, rec, 0)
        ids = builder.block(-1, -1, axiom)
        builder.flush()
        return self._decompose(tree, rec, np.asarray(ids, np.int32), builder.first, 0)

    def _answer_queries(self, tree: DerivationTree, rec: _Record, string: np.ndarray, first: int) -> None:
        """The query modules ``?P ?H ?L ?U`` the last step wrote get the turtle's state there:
        a :class:`Vector3` for one parameter, the coordinates for several (as in L-Py)."""
        from ..interpretation.turtle import QUERIES, turtle_states

        wanted = {self._sym[q]: cols for q, cols in QUERIES.items() if q in self._sym}
        nodes = np.asarray(string, np.int64)
        if not wanted:
            return
        where = np.flatnonzero(np.isin(tree.symbol[nodes], list(wanted)) & (nodes >= first))
        if not where.size:
            return
        states = turtle_states(self, tree, nodes, where)
        start = int(nodes[where].min())
        block = np.asarray(tree.params[start:], float).copy()
        for k, position in enumerate(where.tolist()):
            node = int(nodes[position])
            value = states[k, wanted[rec.syms[node]]]
            count = len(rec.args[node])
            rec.args[node] = (lpy_plantgl.Vector3(value),) if count <= 1 else tuple(value[:count].tolist())
            block[node - start, : min(count, 3)] = value[: min(count, 3)]
        tree.params[start:] = block

    def _hook(self, rec: _Record, name: str, tree: DerivationTree | None = None, string: Any = None) -> None:
        fn = rec.ns.get(name)
        if not callable(fn):
            return
        wants = len([p for p in inspect.signature(fn).parameters.values() if p.default is p.empty])
        args = [[(self.symbols[rec.syms[i]], rec.args[i]) for i in np.asarray(string).tolist()]] if wants else []
        self._call(fn, *args)

    def rewrite(
        self,
        tree: DerivationTree,
        string: np.ndarray,
        step: int,
        rng: np.random.Generator,
        constants: Mapping[str, float],
        rule_constants: dict | None = None,
        frozen: np.ndarray | None = None,
    ) -> np.ndarray:
        """One step of the L-Py rules over ``string`` (node ids of ``tree``); ``frozen`` modules
        are context only.  A regrowth (``frozen`` given) seeds :mod:`random` from ``rng``."""
        rec = self.record(tree)
        del rec.syms[tree.size :], rec.args[tree.size :]  # a regrowth that failed left these
        if frozen is not None:
            random.seed(int(rng.integers(2**31)))
        nodes = np.asarray(string).tolist()
        first = tree.size
        out = self._pass(tree, rec, nodes, "production", step, lambda i, node: frozen is not None and bool(frozen[i]))
        if len(out) > self.max_modules:
            raise DerivationError(f"step {step} would make {len(out):,} modules, more than {self.max_modules:,}")
        return self._decompose(tree, rec, np.asarray(out, np.int32), first, step)

    def _decompose(self, tree: DerivationTree, rec: _Record, string: np.ndarray, first: int, step: int) -> np.ndarray:
        if not rec.rules["decomposition"]:
            return string
        for _ in range(int(rec.ns["__max_depth__"].get("decomposition", 1))):
            size = tree.size
            nodes = string.tolist()
            out = self._pass(tree, rec, nodes, "decomposition", step, lambda i, node, first=first: node < first)
            if tree.size == size:
                break
            string, first = np.asarray(out, np.int32), size
        return string

    def _pass(self, tree: DerivationTree, rec: _Record, nodes: list, section: str, step: int, skip: Callable) -> list:
        """Apply ``section``'s rules to every module of ``nodes`` not skipped; the new string."""
        if section == "production" and rec.rt.backward:
            return self._backward_pass(tree, rec, nodes, step, skip)
        builder = _Builder(self, tree, rec, step)
        context = _Neighbours(self, rec, nodes)
        table = rec.rules[section]
        out: list[int] = []
        i = 0
        while i < len(nodes):
            node = nodes[i]
            hit = None if skip(i, node) or rec.syms[node] not in table else self._apply(rec, table, context, nodes, i, out)
            if hit is None:
                out.append(node)
                i += 1
                continue
            out.extend(builder.block(node, hit[0], hit[1]))
            for other in nodes[i + 1 : i + hit[2]]:  # a predecessor of several modules: the others end
                builder.block(other, hit[0], [])
            i += hit[2]
        builder.flush()
        return out

    def _backward_pass(self, tree: DerivationTree, rec: _Record, nodes: list, step: int, skip: Callable) -> list:
        """L-Py's ``backward()``: the modules are rewritten from the right end, so a ``>>`` context
        reads what this step already produced on the right."""
        builder = _Builder(self, tree, rec, step)
        context = _Neighbours(self, rec, nodes)
        table = rec.rules["production"]
        pieces: list[list[int]] = []
        tail: list[int] = []  # the produced string right of i, rightmost first
        for i in range(len(nodes) - 1, -1, -1):
            node = nodes[i]
            hit = None if skip(i, node) or rec.syms[node] not in table else self._apply(rec, table, context, nodes, i, tail)
            if hit is not None and hit[2] > 1:
                rule = self.translation.rules[hit[0]]
                raise LpyError(
                    "a predecessor of several modules in a backward derivation", rule.line, 1, rule.text, self.filename
                )
            piece = [node] if hit is None else builder.block(node, hit[0], hit[1])
            pieces.append(piece)
            tail.extend(reversed(piece))
        builder.flush()
        return [v for piece in reversed(pieces) for v in piece]

    def _apply(self, rec: _Record, table: dict, context: _Neighbours, nodes: list, i: int, out: list) -> tuple | None:
        """``(rule index, produced modules, modules rewritten)`` of the first rule that applies at ``i``."""
        for k, rule, fn, pred, left, right in table[rec.syms[nodes[i]]]:
            if rule.group and rule.group != rec.rt.group:
                continue
            if (rule.new_right and not rec.rt.backward) or (rule.new_left and rec.rt.backward):
                continue  # a new context on the side not produced yet matches nothing
            args = context.sequence(i, pred)
            if args is None:
                continue
            last = i + len(pred) - 1
            values = context.matched(i, last, [] if rule.new_left else left, [] if rule.new_right else right)
            if values is not None and rule.new_right:  # '>>' (backward): read in what was produced on the right
                after = context.new_right(out, right)
                values = None if after is None else (values[0], after)
            if values is not None and rule.new_left:  # '<<': read in what this step produced so far
                before = context.new_left(out, left)
                values = None if before is None else (before, values[1])
            if values is None:
                continue
            flat = [*values[0], *args, *values[1]]
            if any(j >= len(flat) or flat[j] != v for j, v in rule.equal):
                continue
            rec.rt.buffer = []
            produced = self._call(fn, *flat)
            if produced is not None:
                return k, _checked(produced, rule, self.filename), len(pred)
        return None

    def record(self, tree: DerivationTree) -> _Record:
        """The L-Py side of a history tree this model derived."""
        try:
            return self._records[tree]
        except KeyError:
            raise DerivationError("this history tree was not derived by this L-Py model") from None

    def module_text(self, tree: DerivationTree, node: int) -> str:
        rec = self._records.get(tree)
        if rec is None or node >= len(rec.args):
            return super().module_text(tree, node)
        args = rec.args[node]
        name = self.symbols[rec.syms[node]]
        return name + ("(" + ",".join(_fmt(a) for a in args) + ")" if args else "")

    def interpreted(self, tree: DerivationTree) -> tuple[DerivationTree, np.ndarray, np.ndarray]:
        """``(scratch, string, source)``: the current string through the interpretation rules
        (``maximum depth`` times, default 1), and each drawn module's leaf in ``tree``."""
        rec = self.record(tree)
        leaves = np.asarray(tree.leaves, np.int64)
        scratch = DerivationTree(TABLE_PARAMS, capacity=max(2 * len(leaves), 1024))
        side = _Record(rec.ns, rec.rt, rec.rules)
        self._records[scratch] = side
        builder = _Builder(self, scratch, side, 0)
        builder.block(-1, -1, [(self.symbols[rec.syms[v]], rec.args[v]) for v in leaves.tolist()])
        builder.flush()
        string = list(range(len(leaves)))
        for depth in range(1, int(rec.ns["__max_depth__"].get("interpretation", 1)) + 1):
            size = scratch.size
            string = self._pass(scratch, side, string, "interpretation", depth, lambda i, node: False)
            if scratch.size == size:
                break
        root = np.arange(scratch.size, dtype=np.int64)
        parent = np.asarray(scratch.parent[: scratch.size], np.int64)
        for node in range(len(leaves), scratch.size):
            root[node] = root[parent[node]]
        out = np.asarray(string, np.int32)
        return scratch, out, leaves[root[out]]


class _Builder:
    """New history nodes of one pass, appended to the tree as one block (children contiguous)."""

    def __init__(self, lsystem: LpyLSystem, tree: DerivationTree, rec: _Record, step: int) -> None:
        self.ls, self.tree, self.rec, self.step = lsystem, tree, rec, step
        self.first = self.next = tree.size
        self.rows: list[tuple] = []
        self.blocks: list[tuple[int, int, int]] = []

    def block(self, parent: int, rule: int, modules: list) -> list[int]:
        first = self.next
        for k, module in enumerate(modules):
            if type(module) is not tuple or len(module) != 2:
                message = f"a rule produced {module!r}, not a module (use produce or nproduce)"
                if rule < 0:
                    raise LpyError(message, None, None, None, self.ls.filename)
                where = self.ls.translation.rules[rule]
                raise LpyError(message, where.line, 1, where.text, self.ls.filename)
            name, args = module
            sym = self.ls.intern(name)
            self.rows.append((sym, min(len(args), TABLE_PARAMS), _numbers(args) if args else _NO_NUMBERS, parent, rule, k))
            self.rec.syms.append(sym)
            self.rec.args.append(tuple(args))
        self.next += len(modules)
        if parent >= 0:
            self.blocks.append((parent, first if modules else -1, len(modules)))
        return list(range(first, self.next))

    def flush(self) -> None:
        if self.rows:
            sym, count, values, parent, rule, index = zip(*self.rows)
            self.tree.append(
                np.array(sym, np.int32),
                np.array(count),
                np.array(values),
                np.array(parent),
                self.step,
                np.array(rule),
                np.array(index),
            )
        if self.blocks:
            parents, firsts, counts = (np.array(c, np.int64) for c in zip(*self.blocks))
            self.tree.set_children(parents, firsts, counts)


class _Neighbours:
    """Context modules of a string: branches skipped, the ignore/consider filter applied."""

    def __init__(self, lsystem: LpyLSystem, rec: _Record, nodes: list) -> None:
        self.rec = rec
        self.syms = [rec.syms[v] for v in nodes]
        self.args = [rec.args[v] for v in nodes]
        self.open, self.close = lsystem.intern("["), lsystem.intern("]")
        filters = lsystem.translation.filters
        self.ignore = {lsystem.intern(s) for s in filters.get("ignore", ())}
        self.consider = {lsystem.intern(s) for s in filters.get("consider", ())} or None
        self.match: dict[int, int] | None = None

    def skipped(self, sym: int) -> bool:
        return sym in self.ignore or (self.consider is not None and sym not in self.consider)

    def brackets(self) -> dict[int, int]:
        if self.match is None:
            self.match, stack = {}, []
            for j, s in enumerate(self.syms):
                if s == self.open:
                    stack.append(j)
                elif s == self.close and stack:
                    k = stack.pop()
                    self.match[j], self.match[k] = k, j
        return self.match

    def left(self, i: int, count: int) -> list[int] | None:
        found: list[int] = []
        j = i - 1
        while j >= 0 and len(found) < count:
            s = self.syms[j]
            if s == self.close:
                j = self.brackets().get(j, 0) - 1
            elif s != self.open and not self.skipped(s):
                found.append(j)
                j -= 1
            else:
                j -= 1
        return found[::-1] if len(found) == count else None

    def new_right(self, tail: list, patterns: list) -> list | None:
        """The arguments of the right context ``patterns`` in the produced string ``tail`` (node ids,
        rightmost first), or None."""
        where = self.right(-1, patterns, _Reversed(tail, self.rec.syms))
        if where is None:
            return None
        values: list = []
        modules = [p for p in patterns if p[0] not in (self.open, self.close)]
        for j, (sym, arity) in zip(where, modules):
            node = tail[len(tail) - 1 - j]
            if not _fits(arity, len(self.rec.args[node])):
                return None
            values.extend(self.rec.args[node])
        return values

    def right(self, i: int, patterns: list, syms: Any = None) -> list[int] | None:
        """Positions matching the right context ``patterns`` after ``i`` (``[`` and ``]`` in it as in
        cpfg: ``[`` enters the next branch, ``]`` leaves the rest of the current one), or None."""
        found: list[int] = []
        syms = self.syms if syms is None else syms
        j, size = i + 1, len(syms)
        for sym, _ in patterns:
            while (
                j < size and sym != self.open and syms[j] != self.close and (syms[j] == self.open or self.skipped(syms[j]))
            ):  # branches and filtered modules are skipped on the way to a module
                j = self._branch_end(j + 1, syms) + 1 if syms[j] == self.open else j + 1
            if sym == self.close:
                j = self._branch_end(j, syms) + 1
                continue
            while sym == self.open and j < size and self.skipped(syms[j]):
                j += 1
            if j >= size or syms[j] != sym:
                return None
            if sym != self.open:
                found.append(j)
            j += 1
        return found

    def _branch_end(self, j: int, syms: Any) -> int:
        """The position of the ``]`` that closes the branch position ``j`` is in."""
        depth = 0
        while j < len(syms):
            if syms[j] == self.open:
                depth += 1
            elif syms[j] == self.close:
                if depth == 0:
                    return j
                depth -= 1
            j += 1
        return j

    def new_left(self, out: list, patterns: list) -> list | None:
        """The arguments of the left context ``patterns`` in the new string ``out`` (node ids), or None."""
        rec, j, depth = self.rec, len(out) - 1, 0
        found: list[int] = []
        while j >= 0 and len(found) < len(patterns):
            s = rec.syms[out[j]]
            if s == self.close:
                depth += 1
            elif s == self.open:
                depth = max(depth - 1, 0)
            elif depth == 0 and not self.skipped(s):
                found.append(out[j])
            j -= 1
        if len(found) < len(patterns):
            return None
        values: list = []
        for node, (sym, arity) in zip(found[::-1], patterns):
            if rec.syms[node] != sym or not _fits(arity, len(rec.args[node])):
                return None
            values.extend(rec.args[node])
        return values

    def sequence(self, i: int, patterns: list) -> list | None:
        """The arguments of the modules from ``i`` on if they match ``patterns`` one by one, else None."""
        if i + len(patterns) > len(self.syms):
            return None
        out: list = []
        for j, (sym, arity) in enumerate(patterns, start=i):
            if self.syms[j] != sym or not _fits(arity, len(self.args[j])):
                return None
            out.extend(self.args[j])
        return out

    def matched(self, first: int, last: int, left: list, right: list) -> tuple[list, list] | None:
        values: tuple[list, list] = ([], [])
        for side, patterns, i in ((0, left, first), (1, right, last)):
            if not patterns:
                continue
            where = self.left(i, len(patterns)) if side == 0 else self.right(i, patterns)
            if where is None:
                return None
            modules = [p for p in patterns if p[0] not in (self.open, self.close)]
            for j, (sym, arity) in zip(where, modules):
                if self.syms[j] != sym or not _fits(arity, len(self.args[j])):
                    return None
                values[side].extend(self.args[j])
        return values


class _Reversed:
    """The symbols of node ids read from the end (a backward pass's produced string, in string order)."""

    def __init__(self, nodes: list, syms: list) -> None:
        self.nodes, self.syms = nodes, syms

    def __len__(self) -> int:
        return len(self.nodes)

    def __getitem__(self, j: int) -> int:
        return self.syms[self.nodes[len(self.nodes) - 1 - j]]


class LpyDerivation(Derivation):
    """A derivation of an L-Py model: drawn through its interpretation rules, if any."""

    lsystem: LpyLSystem

    def skeleton(self) -> Skeleton:
        from ..interpretation.turtle import interpret_string

        ls = self.lsystem
        if not ls.record(self.tree).rules["interpretation"]:
            return interpret_string(ls, self.tree, self.tree.leaves)
        scratch, string, source = ls.interpreted(self.tree)
        node_source = np.zeros(scratch.size, np.int64)
        node_source[string] = source
        skeleton = interpret_string(ls, scratch, string)
        _remap(skeleton, node_source)
        skeleton.extra.pop("trace", None)
        return skeleton


def _remap(part: Any, node_source: np.ndarray, depth: int = 0) -> None:
    """Every ``leaf_id`` array in ``part`` (and the dataclasses it holds) as the source leaf ids."""
    if depth > 2 or not is_dataclass(part):
        return
    for f in fields(part):
        value = getattr(part, f.name)
        if f.name == "leaf_id" and isinstance(value, np.ndarray):
            setattr(part, f.name, node_source[value] if len(value) else value.astype(np.int64))
        elif is_dataclass(value):
            _remap(value, node_source, depth + 1)
    for value in getattr(part, "extra", {}).values():
        _remap(value, node_source, depth + 1)


def _split_init(text: str) -> tuple[str, str]:
    """``(main, initialisation)``, each as long as the file (blank lines elsewhere) so lines keep."""
    lines = text.splitlines()
    cut = next((i for i, line in enumerate(lines) if line.startswith(_INIT_MARKS)), len(lines))
    main = "\n".join(lines[:cut]) + "\n"
    init = "\n" * cut + "\n".join(lines[cut:]) + "\n"
    return main, init


def _file_line(exc: BaseException, translation: Translation) -> int | None:
    line = None
    tb = exc.__traceback__
    while tb is not None:
        name = tb.tb_frame.f_code.co_filename
        if name == _MAIN:
            line = translation.origin[min(tb.tb_lineno, len(translation.origin)) - 1]
        elif name == _INIT:
            line = tb.tb_lineno
        tb = tb.tb_next
    return line


def _checked(out: Any, rule: LpyRule, filename: str | None) -> list:
    if isinstance(out, list):  # its items are checked as the builder records them
        return out
    raise LpyError(f"the rule returned {type(out).__name__}, not a produced string", rule.line, 1, rule.text, filename)


def _fits(arity: int | None, count: int) -> bool:
    return arity is None or (count == arity if arity >= 0 else count >= -arity)


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float, np.number)) and not isinstance(v, bool)


_NO_NUMBERS = [math.nan] * TABLE_PARAMS


def _numbers(args: tuple) -> list[float]:
    row = [float(a) if _is_number(a) else math.nan for a in args[:TABLE_PARAMS]]
    return row + [math.nan] * (TABLE_PARAMS - len(row))


def _module_text(module: Any) -> str:
    """``A(1,2)`` for the axiom entry ``('A', (1, 2))``."""
    if isinstance(module, tuple) and len(module) == 2 and isinstance(module[1], tuple):
        name, args = module
        return f"{name}({','.join(_fmt(a) for a in args)})" if args else str(name)
    return str(module)


def _fmt(v: Any) -> str:
    return f"{v:.6g}" if _is_number(v) else repr(v)


def lpy_lsystem(text: str, filename: str | None = None) -> LpyLSystem:
    """Read an ``.lpy`` model (this runs its code: see the module's docstring)."""
    return LpyLSystem(text, filename)


FILE_READERS[".lpy"] = lpy_lsystem
