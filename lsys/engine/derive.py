"""Parallel rewriting with history: :class:`LSystem` and :class:`Derivation`.

One derivation step is vectorised over the whole string: for every rule, the
modules it rewrites are found with array masks, its condition and successor
parameters are evaluated once for all of them (numpy expressions), and the new
string is assembled with one scatter.  Contexts come from each module's nearest
context neighbours, computed once per step for the whole string in one linear
pass (:func:`context_neighbours`).

Rule choice for one module, in order:

1. context-sensitive rules before context-free ones (groups in file order);
2. within a group of rules with the same predecessor and contexts, a
   deterministic group takes the first rule (file order) whose condition holds;
   a stochastic group (rules with probabilities) draws one rule with those
   probabilities, and **if the drawn rule's condition is false the module is
   left unchanged** (it is not redrawn);
3. no rule: the module keeps its node (identity production).

Random numbers (rule draws, ``uniform``/``normal``) come from one seeded
:class:`numpy.random.Generator`, so the same seed gives the same string.

>>> ls = LSystem.from_text("n: 2\\nw: A(1)\\np:\\n A(x) -> A(x+1)B(x+1)C(1)\\n B(y) -> B(y+3)")
>>> ls.derive().to_string()
'A(3)B(3)C(1)B(5)C(1)'
"""

from __future__ import annotations

import functools
import os
import sys
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Self, cast

import numpy as np

import ramure.grammars as grammar_files
from ..errors import DerivationError, GrammarError, ValueRefused
from ..language.cstatements import RuleBlocks, cpfg_blocks
from ..expr import compile_expression, evaluate_constant, seeded_generator
from ..language.grammar import Grammar, parse_grammar, read_grammar_file
from ..language.hidden import Hidden, grammar_hidden, literal_keys, probabilities
from .branch_cut import cut_string
from .combination import split as split_combination
from ..history.decompose import decompose
from ..history.tree import DerivationTree, concat_ranges

if TYPE_CHECKING:
    from ..interpretation.polygons import Polygons
    from ..interpretation.turtle import Skeleton


#: Readers of other model formats: file suffix -> ``reader(text, filename)`` returning an
#: :class:`LSystem`; a reader's module registers itself (``.lpy``: :mod:`ramure.lsys.readers.lpy`).
FILE_READERS: dict[str, Callable[[str, str | None], LSystem]] = {}


@dataclass
class _CompiledRule:
    rule: object
    condition: object  # compiled fn or None
    succ_symbols: np.ndarray
    succ_nparams: np.ndarray
    succ_args: list  # per successor module: list of compiled fns
    sources: dict  # formal name -> (slot, param index); slot 0 = pred, -k = left k, +k = right k
    blocks: Any = None  # a cpfg rule with statement blocks: its RuleBlocks (also its condition)


@dataclass
class _Group:
    symbol: int
    arity: int
    rules: list
    left: list  # [(symbol id, arity)]
    right: list
    cumulative: np.ndarray | None  # for stochastic groups


class LSystem:
    """A grammar ready to derive.  ``constants`` is a plain dict you may edit.

    >>> ls = LSystem.from_text("#define k 2\\nn: 1\\nw: A(1)\\np:\\n A(x) -> A(x*k)")
    >>> ls.constants["k"] = 5
    >>> ls.derive().to_string()
    'A(5)'
    """

    #: A derivation that would grow past this many modules stops with a clear
    #: error instead of exhausting memory (about 150 bytes per module with history).
    max_modules = 20_000_000
    #: The derivation history (every module ever made) may not grow past this many
    #: nodes either: a small string rewritten at every step grows it without bound.
    max_history = 60_000_000
    #: ... and may not hold more than this many parameter values (history nodes times the
    #: grammar's widest module, 8 bytes each): 100-parameter modules reach it at 1.2 M nodes.
    max_values = 120_000_000
    #: More derivation steps than this are refused: a grammar whose string stops
    #: growing would otherwise loop for hours on an absurd ``n``.
    max_steps = 10_000

    def __init__(self, grammar: Grammar) -> None:
        self.grammar = grammar
        self.constants = dict(grammar.constants)
        self.symbols = list(grammar.symbols)
        self._sym = {s: i for i, s in enumerate(self.symbols)}
        self.max_params = max(
            [len(m.args) for m in grammar.axiom]
            + [len(m.args) for r in [*grammar.rules, *grammar.decomposition] for m in r.successor]
            + [1]
        )
        #: Hidden constants (:mod:`ramure.lsys.language.hidden`): literals and rule probabilities a
        #: combination may set like ``#define`` names; without an override, the grammar's values.
        self.hidden: dict[str, Hidden] = grammar_hidden(grammar)
        self._rules = [self._compile(r) for r in grammar.rules]
        #: Rules whose strict predecessor is several modules (cpfg), matched before the groups.
        self._sequences = [r.index for r in grammar.rules if r.sequence]
        self._groups = self._make_groups()
        self.bracket_ids = (self._sym.get("["), self._sym.get("]"))
        self.ignore_ids = {self._sym[s] for s in grammar.ignore if s in self._sym}

    @classmethod
    def from_text(cls, text: str, filename: str | None = None) -> Self:
        """Parse grammar text; L-studio/cpfg text (a ``filename`` ending in ``.l``, or a
        ``derivation length:`` line, never valid ``.lsys``) is read by :mod:`ramure.lsys.language.cpfg`,
        an MTG (a ``filename`` ending in ``.mtg``) becomes a plant by :mod:`ramure.lsys.architecture.mtg_plant`,
        a suffix of :data:`FILE_READERS` (``.lpy``) is read by its reader."""
        from ..language.cpfg import is_cpfg, parse_cpfg

        reader = FILE_READERS.get(os.path.splitext(str(filename))[1].lower()) if filename is not None else None
        if reader is not None:  # e.g. L-Py's .lpy (ramure.lsys.readers.lpy registers itself)
            return cast(Self, reader(text, filename))
        if filename is not None and str(filename).lower().endswith(".mtg"):
            return cls(parse_grammar(_mtg_text_as_grammar(text, str(filename))))
        if is_cpfg(text, filename):
            return cls(parse_cpfg(text, filename))
        return cls(parse_grammar(text, filename))

    def copy(self) -> LSystem:
        """A fresh grammar of the same kind (an ``.lpy`` model stays one) with the file's constants."""
        return LSystem(self.grammar)

    def rule_counts(self) -> dict[str, int]:
        """How many rules each section holds: production, decomposition, interpretation."""
        g = self.grammar
        return {"production": len(g.rules), "decomposition": len(g.decomposition), "interpretation": len(g.interpretation)}

    @classmethod
    def from_file(cls, path: str | os.PathLike) -> Self:
        """Load a grammar file; a shipped grammar's name (``"honda_sympodial"``) works too.

        A path that exists wins; ``"grammars/NAME.lsys"`` that does not exist here falls
        back to the shipped grammar of that name, so examples work from any directory.
        """
        file = grammar_files.resolve(path)
        if file.suffix.lower() == ".mtg":  # Latin-1 MTG files are common: read by the MTG reader
            from ..architecture.mtg_graph import read_mtg_graph
            from ..architecture.mtg_plant import mtg_grammar_text

            return cls(parse_grammar(mtg_grammar_text(read_mtg_graph(file), where=str(file))))
        text = read_grammar_file(file)
        return cls.from_text(text, filename=str(file))

    @classmethod
    def file_polygons(cls, path: str | os.PathLike) -> Polygons:
        """The polygons the grammar file ``path`` draws, derived at its own ``n`` (a ``#surface "file"``)."""
        return cls.from_file(path).derive().skeleton().polygons

    @property
    def n(self) -> int:
        return self.grammar.n

    @property
    def seed(self) -> int:
        """The grammar's ``#seed`` (0 when the text has none): the seed :meth:`derive` and a
        :class:`~ramure.lsys.regeneration.regen.Session` use unless given one."""
        return 0 if self.grammar.seed is None else int(self.grammar.seed)

    @property
    def text(self) -> str:
        return self.grammar.text

    # -- compilation -------------------------------------------------------
    def _compile(self, rule):
        formals, consts = rule.formals, self.constants
        sources: dict[str, tuple[int | str, int]] = {}  # slot: 0, -k / +k contexts, "s1"... a predecessor's later modules
        for k, pattern in enumerate(reversed(rule.left), start=1):
            for j, name in enumerate(pattern.params):
                sources[name] = (-k, j)
        for j, name in enumerate(rule.pred.params):
            sources[name] = (0, j)
        for m, pattern in enumerate(rule.sequence, start=1):  # the strict predecessor's later modules
            for j, name in enumerate(pattern.params):
                sources[name] = (f"s{m}", j)
        for k, pattern in enumerate(rule.right, start=1):
            for j, name in enumerate(pattern.params):
                sources[name] = (k, j)
        cond = compile_expression(rule.condition, formals, consts) if rule.condition else None
        hidden = getattr(self, "hidden", {})
        succ_args = [
            [compile_expression(a, formals, consts, literal_keys(hidden, rule.index, j, k)) for k, a in enumerate(m.args)]
            for j, m in enumerate(rule.successor)
        ]
        blocks = None
        if rule.blocks is not None:  # cpfg: run module by module (cstatements.RuleBlocks)
            pre, post = rule.blocks
            blocks = RuleBlocks(pre, post, cond, succ_args, formals)
            cond = blocks
        return _CompiledRule(
            rule=rule,
            condition=cond,
            succ_symbols=np.array([self._sym[m.symbol] for m in rule.successor], np.int32),
            succ_nparams=np.array([len(m.args) for m in rule.successor], np.int8),
            succ_args=succ_args,
            sources=sources,
            blocks=blocks,
        )

    def _make_groups(self):
        groups: dict[tuple, list[int]] = {}
        for rule in self.grammar.rules:
            if not rule.sequence:  # several-module predecessors: _choose_sequences
                groups.setdefault(rule.group_key(), []).append(rule.index)
        out = []
        for (sym, arity, left, right), members in groups.items():
            probs = [self.grammar.rules[i].probability for i in members]
            cumulative = None if probs[0] is None else np.cumsum(probs)
            if cumulative is not None:
                cumulative[-1] = 1.0 + 1e-12
            out.append(
                _Group(
                    self._sym[sym],
                    arity,
                    members,
                    [(self._sym[s], a) for s, a in left],
                    [(self._sym[s], a) for s, a in right],
                    cumulative,
                )
            )
        # Context-sensitive groups first; file order otherwise.
        out.sort(key=lambda g: (not (g.left or g.right), g.rules[0]))
        return out

    # -- deriving ----------------------------------------------------------
    def derive(
        self,
        n: int | None = None,
        seed: int | None = None,
        constants: Mapping[str, float] | None = None,
        params: dict | None = None,
        progress: Callable[[int, int], None] | None = None,
    ) -> Derivation:
        """Derive ``n`` steps (default: the grammar's ``n:``) from the axiom, with random ``seed``
        (default: the grammar's ``#seed``, else 0).

        ``constants`` overrides constant values for this derivation;
        ``params`` is a parameter combination ``{"rule": r or None, "constants": {...}}``
        (:mod:`ramure.lsys.engine.combination`): with a rule, its constants apply to that
        rule only (the variant explorer's "one rule at a time").
        """
        combo, (extra, rule_constants) = params, split_combination(params)
        constants = {**(constants or {}), **extra}
        n = self.grammar.n if n is None else int(n)
        if n < 0:
            raise GrammarError(f"the derivation count must be >= 0, not {n}")
        if n > self.max_steps:
            raise DerivationError(
                f"{n} derivation steps are more than the limit of {self.max_steps:,}: "
                "use fewer steps (or raise LSystem.max_steps)"
            )
        seed = self.seed if seed is None else check_seed(seed)
        consts = {**self.constants, **(constants or {})}
        check_constants(consts)
        unknown = set(constants or {}) - set(self.constants) - set(self.hidden)
        for overrides in (rule_constants or {}).values():
            unknown |= set(overrides) - set(self.constants) - set(self.hidden)
        if unknown:
            raise GrammarError(
                f"unknown constant(s): {', '.join(sorted(unknown))}; the grammar defines {', '.join(self.constants) or 'none'}"
            )
        from ..interpretation.turtle import answer_queries  # lazily: the turtle needs no derivation to load

        blocks = cpfg_blocks(self.grammar, consts, seed)
        blocks.run("define", "start")  # cpfg's blocks, if any: the globals live in consts
        tree = DerivationTree(self.max_params, capacity=4096)
        axiom = self.grammar.axiom
        values = np.full((len(axiom), tree.max_params), np.nan)
        for i, spec in enumerate(axiom):
            for j, arg in enumerate(spec.args):
                key = f"~w{i}.{j}"  # an axiom literal a combination overrides (ramure.lsys.language.hidden)
                values[i, j] = consts[key] if key in consts else evaluate_constant(arg, consts)
        ids = tree.append(
            [self._sym[m.symbol] for m in axiom], [len(m.args) for m in axiom], values, -1, 0, -1, np.arange(len(axiom))
        )
        tree.leaves = ids
        rng = seeded_generator(seed)
        string = decompose(self, tree, ids, 0, 0, rng, consts)  # the axiom too (no decomposition: ids)
        string = cut_string(self, tree, string)  # '%' cuts the rest of its branch (ramure.lsys.engine.branch_cut)
        answer_queries(self, tree, string)  # ?P ?H ?L ?U, if any
        for step in range(1, n + 1):
            blocks.run("starteach")
            made = tree.size
            string = self.rewrite(tree, string, step, rng, consts, rule_constants)
            answer_queries(self, tree, string, made)
            blocks.run("endeach")
            if progress is not None:
                progress(step, n)
        blocks.run("end")
        tree.leaves = string
        tree.compact_params()  # the later parameters kept only where a node has them
        tree.changed()
        derivation = Derivation(self, tree, n=n, seed=seed, constants=consts, params=combo)
        derivation.printed = blocks.scope.printed if blocks.scope else []
        return derivation

    @property
    def has_context(self) -> bool:
        """True when some rule (production or decomposition) has a left or right context."""
        return any(r.is_context_sensitive for r in [*self.grammar.rules, *self.grammar.decomposition])

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
        """One parallel rewriting step of ``string`` (node ids); returns the new string.

        ``frozen`` (a boolean mask) marks modules that serve only as context:
        they are never rewritten.
        """
        string = string.astype(np.int32, copy=False)  # the tree's string dtype: one compiled assemble
        symbols = tree.symbol[string]
        nparams = tree.nparams[string]
        chosen = np.full(len(string), -1, np.int32)
        free = np.ones(len(string), bool) if frozen is None else ~frozen
        context: dict = {}
        if self._sequences:
            self._choose_sequences(tree, string, symbols, nparams, free, chosen, context, rng, constants, rule_constants)
        by_symbol: dict[int, np.ndarray] = {}
        for group in self._choice_plan(len(string)):
            if isinstance(group, _Run):
                self._choose_run(group, symbols, nparams, free, chosen, context)
                continue
            if group.symbol not in by_symbol:
                by_symbol[group.symbol] = np.flatnonzero(symbols == group.symbol)
            cand = by_symbol[group.symbol]
            cand = cand[(nparams[cand] == group.arity) & (chosen[cand] < 0) & free[cand]]
            if not cand.size:
                continue
            ctx = None
            if group.left or group.right:
                cand, ctx = self._match_context(group, cand, symbols, nparams, string, context)
                if not cand.size:
                    continue
            self._choose(group, cand, ctx, chosen, tree, string, rng, constants, rule_constants)
        made = tree.size
        out = self._assemble(tree, string, chosen, step, rng, constants, rule_constants, context)
        out = decompose(
            self,
            tree,
            out,
            made,
            step,
            rng,
            constants,  # decomposition rules, if any
            None if frozen is None else string[frozen],
        )
        return cut_string(self, tree, out, frozen)  # '%' cuts the rest of its branch

    def _choice_plan(self, length):
        """The groups in matching order; on long strings, consecutive groups that take every
        module they match are merged into one :class:`_Run` (matched in one compiled pass)."""
        if not self.fused_choice or not self._use_kernels(length):
            return self._groups
        plan = self.__dict__.get("_plan")
        if plan is None or plan[0] is not self._groups:
            plan = (self._groups, _Run.merge(self._groups, self._rules))
            self._plan = plan
        return plan[1]

    def _choose_run(self, run, symbols, nparams, free, chosen, cache) -> None:
        """Match a run of take-every-match groups at once (:func:`~._context_kernel.choose_first_match`)."""
        from ._context_kernel import choose_first_match, reach

        left = right = np.zeros(0, np.int32)
        if run.has_context:
            if "reach" not in cache:
                cache["reach"] = reach(
                    symbols,
                    *(-1 if b is None else b for b in self.bracket_ids),
                    _ignored_table(symbols, self.ignore_ids),
                )
            left, right = cache["reach"]
        choose_first_match(
            symbols,
            nparams,
            free,
            chosen,
            left,
            right,
            run.symbol_start,
            run.symbol_groups,
            run.arity,
            run.rule,
            run.context_start,
            run.want_sym,
            run.want_arity,
            run.sides,
        )

    def _choose_sequences(self, tree, string, symbols, nparams, free, chosen, cache, rng, constants, rule_constants) -> None:
        """cpfg's several-module strict predecessors (``XF(x) --> ...``), before the other rules.

        As cpfg reads a string, left to right: at each position the first such rule (file
        order) whose modules follow each other there (same symbols and numbers of parameters,
        nothing skipped), whose contexts match (the left one before its first module, the right
        one after its last) and whose condition holds takes those modules; the scan goes on
        after them, so matches never overlap.  The first module gets the successor; the others
        get none (in the history they end, like a module rewritten by ``*``).  One-module
        rules then rewrite the modules no such rule took: where both could apply at one
        position the several-module rule wins (cpfg would try them in file order).
        """
        erased = len(self._rules)  # the successor table's empty entry
        evaluate = functools.partial(self._evaluate, rule_constants=rule_constants, constants=constants, rng=rng)
        found, matches = self._sequence_matches(tree, string, symbols, nparams, free, cache, evaluate)
        accepted: dict[int, list[int]] = {}
        rows: dict[int, list] = {}
        end = -1
        for pos, r in found:
            crule = self._rules[r]
            if pos <= end:
                continue
            if crule.blocks is not None:  # statement blocks run module by module, in string order
                cand, ctx = matches[r]
                i = int(np.searchsorted(cand, pos))
                at, one = cand[i : i + 1], {slot: nodes[i : i + 1] for slot, nodes in ctx.items()}
                V = self._variables(crule, at, one, tree, string)
                if not evaluate(crule.condition, V, r, n=1, tree=tree, string=string, pos=at, what="condition")[0]:
                    continue
                rows.setdefault(r, []).extend(crule.blocks.take())
            end = pos + len(crule.rule.sequence)
            chosen[pos] = r
            chosen[pos + 1 : end + 1] = erased
            accepted.setdefault(r, []).append(pos)
        for r, positions in accepted.items():
            cand, ctx = matches[r]
            at = np.searchsorted(cand, positions)
            cache[r] = {"pos": cand[at], **{slot: nodes[at] for slot, nodes in ctx.items()}}
            if r in rows:
                self._rules[r].blocks.rows = rows[r]  # what _successor_params takes, in string order

    def _sequence_matches(self, tree, string, symbols, nparams, free, cache, evaluate):
        """Every several-module rule's matches: ([(position, rule)] sorted, whose condition
        (without statement blocks) holds, and {rule: (positions, context nodes)})."""
        found: list[tuple[int, int]] = []
        matches: dict[int, tuple[np.ndarray, dict]] = {}
        for r in self._sequences:
            cand, ctx = self._sequence_candidates(self.grammar.rules[r], symbols, nparams, free, string, cache)
            if not cand.size:
                continue
            crule, ok = self._rules[r], np.ones(cand.size, bool)
            if crule.condition is not None and crule.blocks is None:  # all at once
                V = self._variables(crule, cand, ctx, tree, string)
                ok = evaluate(crule.condition, V, r, n=cand.size, tree=tree, string=string, pos=cand, what="condition")
            matches[r] = (cand, ctx)
            found.extend((int(p), r) for p in cand[np.asarray(ok, bool)])
        return sorted(found), matches

    def _sequence_candidates(self, rule, symbols, nparams, free, string, cache):
        """Where ``rule``'s strict predecessor (several modules) and contexts match: (first
        positions, {slot: node ids}) with slots ``s1``... for its later modules, -1... and 1...
        for its left and right context modules."""
        strict, n = rule.strict, len(symbols)
        k = len(strict)
        ok = np.ones(max(n - k + 1, 0), bool)
        for m, pattern in enumerate(strict):
            window = slice(m, m + ok.size)
            ok &= (symbols[window] == self._sym[pattern.symbol]) & (nparams[window] == len(pattern.params)) & free[window]
        cand = np.flatnonzero(ok)
        slots: dict[int | str, np.ndarray] = {f"s{m}": cand + m for m in range(1, k)}
        if cand.size and (rule.left or rule.right):
            if "neighbours" not in cache:
                cache["neighbours"] = context_neighbours(symbols, *self.bracket_ids, self.ignore_ids)
            good = np.ones(cand.size, bool)
            for side, patterns, start in ((-1, rule.left[::-1], cand), (1, rule.right, cand + k - 1)):
                if patterns:
                    hit, at = self._side_context(patterns, side, start, symbols, nparams, cache["neighbours"])
                    good &= hit
                    slots.update({side * (j + 1): row for j, row in enumerate(at)})
            cand = cand[good]
            slots = {slot: positions[good] for slot, positions in slots.items()}
        return cand, {slot: string[positions] for slot, positions in slots.items()}

    def _side_context(self, patterns, side, start, symbols, nparams, neighbours):
        """(ok, positions per context module) of one side's context, walked from ``start``."""
        from ._context_kernel import match_contexts

        want = np.array([self._sym[p.symbol] for p in patterns], np.int64)
        arity = np.array([len(p.params) for p in patterns], np.int64)
        sides = np.full(len(patterns), side, np.int64)
        return match_contexts(start, *neighbours, symbols, nparams, want, arity, sides)

    def _variables(self, crule, positions, ctx_nodes, tree, string):
        nodes = string[positions]
        V = {}
        for name, (slot, j) in crule.sources.items():
            src = nodes if slot == 0 else ctx_nodes[slot]
            V[name] = tree.params[src, j]
        return V

    def _choose(self, group, cand, ctx, chosen, tree, string, rng, constants, rule_constants) -> None:
        if group.cumulative is not None:
            cumulative = group.cumulative
            probs = [self.grammar.rules[r].probability for r in group.rules]
            changed = probabilities(group.rules, probs, rule_constants)
            if changed is not None:  # a variant's rule probability (ramure.lsys.language.hidden)
                cumulative = np.cumsum(changed)
                cumulative[-1] = 1.0 + 1e-12
            draws = np.searchsorted(cumulative, rng.random(cand.size), side="right")
            subsets = [(r, draws == k) for k, r in enumerate(group.rules)]
        else:
            subsets = [(r, None) for r in group.rules]
        for r, mask in subsets:
            keep = np.ones(cand.size, bool) if mask is None else mask.copy()
            keep &= chosen[cand] < 0
            if not keep.any():
                continue
            crule = self._rules[r]
            pos = cand[keep]
            if crule.condition is not None:
                sub_ctx = {k: v[keep] for k, v in ctx.items()} if ctx else None
                V = self._variables(crule, pos, sub_ctx, tree, string)
                ok = self._evaluate(
                    crule.condition, V, r, rule_constants, constants, rng, pos.size, tree, string, pos, "condition"
                ).astype(bool)
                pos = pos[ok]
            chosen[pos] = r

    def _evaluate(self, fn, V, r, rule_constants, constants, rng, n, tree, string, pos, what):
        C = constants if not rule_constants or r not in rule_constants else {**constants, **rule_constants[r]}
        with np.errstate(divide="raise", invalid="raise", over="raise"):
            try:
                return fn(V, C, rng, n)
            except (FloatingPointError, ZeroDivisionError, ValueError, OverflowError) as exc:
                bad = self._first_failing(fn, V, C, n)
                module = self.module_text(tree, string[pos[bad]])
                rule = self.grammar.rules[r]
                if isinstance(exc, (ValueError, OverflowError)):  # e.g. normal(0, -1)
                    problem = f"invalid arguments ({exc})"
                elif "divide" in str(exc) or isinstance(exc, ZeroDivisionError):
                    problem = "division by zero"
                else:
                    problem = f"invalid arithmetic ({exc})"
                raise DerivationError(
                    f"{problem} in the {what} of rule {r + 1} ({rule}) while rewriting {module}",
                    rule.line,
                    rule.pred.column,
                    rule.source_line,
                ) from None

    @staticmethod
    def _first_failing(fn, V, C, n):
        with np.errstate(all="raise"):
            for i in range(n):
                try:
                    fn({k: v[i : i + 1] for k, v in V.items()}, C, seeded_generator(0), 1)
                except (FloatingPointError, ZeroDivisionError, ValueError, OverflowError):
                    return i
        return 0

    #: On long strings, groups that take every module they match (deterministic, first
    #: rule without a condition, no context parameters read) are matched in one compiled
    #: pass; False keeps group-by-group matching (what a subclass with its own matcher needs).
    fused_choice = True

    #: Steps on strings at least this long assemble in one compiled pass
    #: (:mod:`ramure.lsys.engine._derive_kernel`); shorter ones with numpy, without loading numba
    #: (once numba is loaded, from :attr:`kernel_loaded_min_modules` modules).
    kernel_min_modules = 50_000
    kernel_loaded_min_modules = 2_000

    def _use_kernels(self, length):
        """True when a step on ``length`` modules should use the compiled kernels."""
        if length >= self.kernel_min_modules:
            return True
        return length >= self.kernel_loaded_min_modules and "ramure.lsys.engine._derive_kernel" in sys.modules

    def _assemble(self, tree, string, chosen, step, rng, constants, rule_constants, context):
        """The new string; the new history nodes are appended as one block.

        New node ids are grouped by rule (ascending rule index), then by string
        position; successor parameters are evaluated rule by rule in that order
        (so random draws follow it).  The successor modules come from one flat
        table of all rules' successors.
        """
        table = self._successor_table()
        nrules = len(self._rules)
        counts = np.bincount(chosen + 1, minlength=nrules + 2)[1 : nrules + 1]  # chosen == nrules: erased
        made = counts * table.length[:-1]
        total = len(string) + int(made.sum()) - int(np.count_nonzero(chosen >= 0))
        if total > self.max_modules:
            raise DerivationError(
                f"step {step} would make {total:,} modules, more than the limit of "
                f"{self.max_modules:,}: use fewer derivation steps (or raise LSystem.max_modules)"
            )
        new = int(made.sum())
        history = tree.size + new
        if history > self.max_history:
            # A string that stays small but is rewritten at every step still grows the history.
            raise DerivationError(
                f"step {step} would make the derivation history {history:,} modules long, more than "
                f"the limit of {self.max_history:,}: use fewer derivation steps "
                "(or raise LSystem.max_history)"
            )
        if history * tree.max_params > self.max_values:
            raise DerivationError(
                f"step {step} would make the derivation history hold {history * tree.max_params:,} parameter "
                f"values ({history:,} modules x {tree.max_params} parameters), more than the limit of "
                f"{self.max_values:,}: use fewer derivation steps or parameters (or raise LSystem.max_values)"
            )
        params = self._successor_params(tree, string, chosen, counts, rng, constants, rule_constants, context)
        self._widen(tree, table)
        start = tree.extend(new, step)
        base = start + np.cumsum(made) - made
        out = np.empty(total, np.int32)  # the string's node ids, as the tree keeps them
        if self._use_kernels(len(string)):
            from ._derive_kernel import assemble

            assemble(
                string,
                chosen,
                table.length,
                table.offset,
                table.symbol,
                table.nparams,
                base,
                out,
                tree.symbol,
                tree.nparams,
                tree.parent,
                tree.rule,
                tree.index_in_rule,
                tree.child_start,
                tree.child_count,
            )
        else:
            self._assemble_numpy(tree, string, chosen, table, start, out)
        tree.params[start:] = params
        tree.changed()
        return out

    @staticmethod
    def _widen(tree, table) -> None:
        """Let the tree's int16 fields hold what a step of this grammar writes
        (:meth:`DerivationTree.widen`): its rule indices, successor symbols, slots and lengths."""
        longest = int(table.length.max())
        tree.widen("rule", 0, len(table.length) - 2)
        tree.widen("index_in_rule", 0, max(longest - 1, 0))
        tree.widen("child_count", 0, longest)
        tree.widen("symbol", 0, int(table.symbol.max()))

    @staticmethod
    def _assemble_numpy(tree, string, chosen, table, start, out) -> None:
        """What :func:`ramure.lsys.engine._derive_kernel.assemble` does, in whole-array numpy steps."""
        pos = np.flatnonzero(chosen >= 0)
        rules = chosen[pos]
        order = _group_order(rules, len(table.length))
        pos, rules = pos[order], rules[order]
        k = table.length[rules]
        lengths = np.ones(len(string), np.int64)
        lengths[pos] = k
        offsets = np.cumsum(lengths) - lengths
        keep = chosen < 0
        out[offsets[keep]] = string[keep]
        parents = string[pos]
        flat = concat_ranges(table.offset[rules], k)
        index = flat - np.repeat(table.offset[rules], k)
        ids = start + np.arange(len(flat), dtype=np.int64)
        tree.symbol[start:] = table.symbol[flat]
        tree.nparams[start:] = table.nparams[flat]
        tree.parent[start:] = np.repeat(parents, k)
        tree.rule[start:] = np.repeat(rules, k)
        tree.index_in_rule[start:] = index
        first = start + np.cumsum(k) - k
        tree.set_children(parents, np.where(k > 0, first, -1), k)
        out[np.repeat(offsets[pos], k) + index] = ids

    def _successor_params(self, tree, string, chosen, counts, rng, constants, rule_constants, context):
        """Parameters of the new modules (rows in new-node order, NaN where unused), rule by rule."""
        table = self._successor_table()
        # column by column in memory (a transposed view): the tree stores parameters by column
        params = np.full((tree.max_params, int(counts @ table.length[:-1])), np.nan).T
        active = np.flatnonzero(counts).tolist()
        if not any(any(self._rules[r].succ_args) for r in active):
            return params
        pos = np.flatnonzero(chosen >= 0)
        pos = pos[_group_order(chosen[pos], len(self._rules))]
        bounds = np.concatenate([[0], np.cumsum(counts)])
        row = 0
        for r in active:
            crule = self._rules[r]
            at = pos[bounds[r] : bounds[r + 1]]
            m, width = at.size, len(crule.succ_symbols)
            rows = slice(row, row + m * width)
            row += m * width
            if not any(crule.succ_args):  # also an empty successor: no rows, nothing to reshape
                continue
            block = params[rows].reshape(m, width, -1)
            if crule.blocks is not None:  # computed with the blocks, module by module
                for i, module in enumerate(crule.blocks.take()):
                    for j, values in enumerate(module):
                        block[i, j, : len(values)] = values
                continue
            ctx = context.get(r)
            ctx_nodes = None
            if ctx is not None:
                ctx_nodes = {s: v[np.searchsorted(ctx["pos"], at)] for s, v in ctx.items() if s != "pos"}
            V = self._variables(crule, at, ctx_nodes, tree, string)
            for j, args in enumerate(crule.succ_args):
                for a, fn in enumerate(args):
                    block[:, j, a] = self._evaluate(fn, V, r, rule_constants, constants, rng, m, tree, string, at, "successor")
        return params

    def _successor_table(self):
        """Every rule's successor in one flat table: ``length``, ``offset``, ``symbol``, ``nparams``."""
        table = self.__dict__.get("_table")
        if table is None or table.rules is not self._rules:
            table = _SuccessorTable(self._rules)
            self._table = table
        return table

    # -- context -----------------------------------------------------------
    def _match_context(self, group, cand, symbols, nparams, string, cache):
        """The candidates whose contexts match ``group``'s, and their context nodes by slot.

        Every module's nearest context neighbours are computed once per step for
        the whole string (:func:`context_neighbours`, linear); a k-module context
        follows them k times.  A wanted symbol or arity of -1 matches anything.
        """
        if "neighbours" not in cache:
            cache["neighbours"] = context_neighbours(symbols, *self.bracket_ids, self.ignore_ids)
        from ._context_kernel import match_contexts

        prev, nxt = cache["neighbours"]
        wanted = list(reversed(group.left)) + list(group.right)
        slots = [-k for k in range(1, len(group.left) + 1)] + list(range(1, len(group.right) + 1))
        ok, at = match_contexts(
            cand,
            prev,
            nxt,
            symbols,
            nparams,
            np.array([w[0] for w in wanted], np.int64),
            np.array([w[1] for w in wanted], np.int64),
            np.sign(slots).astype(np.int64),
        )
        # Context nodes are kept only for rules that read context parameters (``A(x) < B -> ...``).
        used = {slot for r in group.rules for slot, _ in self._rules[r].sources.values() if slot}
        cand = cand[ok]
        ctx: dict[Any, np.ndarray] = {s: string[v[ok]] for s, v in zip(slots, at) if s in used}
        for r in group.rules:
            cache[r] = {"pos": cand, **ctx}
        return cand, ctx

    # -- display -----------------------------------------------------------
    def module_text(self, tree: DerivationTree, node: int) -> str:
        k = int(tree.nparams[node])
        name = self.symbols[tree.symbol[node]]
        if not k:
            return name
        return name + "(" + ",".join(_fmt(v) for v in tree.params[node, :k]) + ")"


class _Run:
    """Consecutive groups matched in one pass: tables for ``choose_first_match``."""

    def __init__(self, groups) -> None:
        top = max(g.symbol for g in groups) + 1
        by_symbol = [[k for k, g in enumerate(groups) if g.symbol == s] for s in range(top)]
        self.symbol_start = np.concatenate([[0], np.cumsum([len(b) for b in by_symbol])]).astype(np.int64)
        self.symbol_groups = np.array([k for b in by_symbol for k in b], np.int64)
        self.arity = np.array([g.arity for g in groups], np.int64)
        self.rule = np.array([g.rules[0] for g in groups], np.int32)
        wanted = [list(reversed(g.left)) + list(g.right) for g in groups]
        self.context_start = np.concatenate([[0], np.cumsum([len(w) for w in wanted])]).astype(np.int64)
        flat = [c for w in wanted for c in w]
        self.want_sym = np.array([c[0] for c in flat], np.int64)
        self.want_arity = np.array([c[1] for c in flat], np.int64)
        self.sides = np.array([s for g in groups for s in [-1] * len(g.left) + [1] * len(g.right)], np.int64)
        self.has_context = bool(flat)

    @staticmethod
    def takes_all(group, rules) -> bool:
        """True when the group rewrites every module it matches with its first rule."""
        first = rules[group.rules[0]]
        return group.cumulative is None and first.condition is None and not any(slot for slot, _ in first.sources.values())

    @classmethod
    def merge(cls, groups, rules):
        """``groups`` with each stretch of consecutive take-all groups replaced by one run."""
        plan, stretch = [], []
        for group in groups + [None]:
            if group is not None and cls.takes_all(group, rules):
                stretch.append(group)
                continue
            if stretch:
                plan.append(cls(stretch))
                stretch = []
            if group is not None:
                plan.append(group)
        return plan


class _SuccessorTable:
    """The successors of all rules concatenated (see :meth:`LSystem._assemble`)."""

    def __init__(self, rules) -> None:
        self.rules = rules
        self.length = np.array([len(c.succ_symbols) for c in rules] + [0], np.int64)
        self.offset = np.concatenate([[0], np.cumsum(self.length)[:-1]]).astype(np.int64)
        self.symbol = np.concatenate([c.succ_symbols for c in rules] + [np.zeros(1, np.int32)])
        self.nparams = np.concatenate([c.succ_nparams for c in rules] + [np.zeros(1, np.int8)])


def _group_order(keys, count):
    """Stable order grouping ``keys`` (whole numbers below ``count``): a radix sort when they fit 16 bits."""
    if count < 2**15:
        keys = keys.astype(np.int16)
    return np.argsort(keys, kind="stable")


def check_seed(seed: int) -> int:
    """A random seed must be a whole number >= 0 (what numpy accepts); returns it as int."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < 2**64:
        raise ValueRefused(f"a seed must be a whole number from 0 to 2^64 - 1, not {seed!r}")
    return int(seed)


def check_constants(constants: Mapping[str, float]) -> Mapping[str, float]:
    """Constant values must be finite numbers; refuses NaN, infinities and non-numbers."""
    for name, value in constants.items():
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) or not np.isfinite(value):
            raise ValueRefused(f"constant {name} must be a finite number, not {value!r}")
    return constants


def context_neighbours(
    symbols: np.ndarray, open_id: int | None, close_id: int | None, ignore_ids: Collection[int]
) -> tuple[np.ndarray, np.ndarray]:
    """(prev, next): each module's nearest left / right context module (-1 for none).

    Linear in the string length (see :mod:`ramure.lsys.engine._context_kernel`):
    ``#ignore`` symbols are skipped, whole branches are jumped over, a left
    context may be found across ``[`` (in the parent branch), a right context
    never across ``]``.
    """
    from ._context_kernel import neighbours

    symbols = np.asarray(symbols)
    ignored = _ignored_table(symbols, ignore_ids)
    match = bracket_matches(symbols, open_id, close_id)
    return neighbours(
        symbols.astype(np.int64), match, -1 if open_id is None else open_id, -1 if close_id is None else close_id, ignored
    )


def _ignored_table(symbols, ignore_ids):
    """A boolean table by symbol id: True for ``#ignore`` symbols."""
    size = int(symbols.max(initial=0)) + 1
    ignored = np.zeros(max(size, max(ignore_ids, default=0) + 1), bool)
    ignored[list(ignore_ids)] = True
    return ignored


def bracket_matches(symbols: np.ndarray, open_id: int | None, close_id: int | None) -> np.ndarray:
    """For each ``[`` the position of its ``]`` and vice versa (-1 elsewhere), one linear pass.

    A ``]`` closes the nearest open ``[``; unbalanced brackets (a piece of a
    string) stay -1.
    """
    if open_id is None or close_id is None:
        return np.full(len(symbols), -1, np.int64)
    from ..interpretation.turtle import bracket_pairs

    match, _ = bracket_pairs(np.asarray(symbols), open_id, close_id)
    return match


def _fmt(v) -> str:
    return f"{v:.6g}"


class Derivation:
    """The result of :meth:`LSystem.derive`: the history tree and its current string."""

    def __init__(
        self, lsystem: LSystem, tree: DerivationTree, n: int, seed: int, constants: dict[str, float], params: dict | None = None
    ) -> None:
        self.lsystem = lsystem
        self.tree = tree
        self.n = n
        self.seed = seed
        self.constants = constants
        self.params = params  # the parameter combination derived with (ramure.lsys.engine.combination), or None
        self.printed: list[str] = []  # what a cpfg file's printf statements printed while deriving

    @property
    def leaves(self) -> np.ndarray:
        """Node ids of the current string, in order."""
        return self.tree.leaves

    def __len__(self) -> int:
        return len(self.tree.leaves)

    @property
    def symbols(self) -> list[str]:
        """Symbol name of each module of the current string."""
        return [self.lsystem.symbols[s] for s in self.tree.symbol[self.tree.leaves]]

    @property
    def modules(self) -> list[tuple[str, tuple[float, ...]]]:
        """The current string as ``(symbol, params)`` pairs (convenient, not fast)."""
        tree, names = self.tree, self.lsystem.symbols
        leaves = tree.leaves
        syms, counts, params = tree.symbol[leaves], tree.nparams[leaves], tree.params[leaves]
        return [(names[s], tuple(p[:k].tolist())) for s, k, p in zip(syms, counts, params)]

    def to_string(self, sep: str = "") -> str:
        """The current string, e.g. ``A(3)B(3)C(1)B(5)C(1)``."""
        return sep.join(self.lsystem.module_text(self.tree, v) for v in self.tree.leaves.tolist())

    def count(self, symbol: str) -> int:
        """How many modules of the current string have this symbol."""
        if symbol not in self.lsystem.symbols:
            return 0
        return int(np.count_nonzero(self.tree.symbol[self.tree.leaves] == self.lsystem.symbols.index(symbol)))

    def skeleton(self) -> Skeleton:
        """Interpret the string with the 3D turtle (see :mod:`ramure.lsys.interpretation.turtle`)."""
        from ..interpretation.turtle import interpret

        return interpret(self)


def _mtg_text_as_grammar(text: str, filename: str) -> str:
    from ..architecture.mtg_graph import parse_mtg_graph
    from ..architecture.mtg_plant import mtg_grammar_text

    return mtg_grammar_text(parse_mtg_graph(text, filename), where=filename)
