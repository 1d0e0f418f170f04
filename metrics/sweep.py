"""The variant sweep: derive every variant, measure it, compare it with the base plant.

:class:`VariantSweep` is configured, then fitted on a grammar, then queried
(scikit-learn style; fitted state ends with ``_``).  Per variant the work is
derive -> skeleton -> ten metrics (no mesh).  Variants go to workers in
chunks (one task = ``chunk_size`` variants; the grammar is parsed once per
worker process), on a local process pool by default or on a Dask cluster
with ``scheduler="tcp://host:port"`` (``pip install ramure[dask]``).

Only distinct plants are derived: a variant changes constants on one rule,
so constants that rule never reads change nothing; variants agreeing on the
ones it reads share one derivation, and variants changing none of them are
the base plant (see :func:`ramure.metrics.variants.distinct_variants`).  On Honda
monopodial that is 405 derivations for 2,187 variants.

A ``progress(done, total)`` callback (counting the derivations actually
run, starting with ``(0, total)``) is called as chunks finish, and the
sweep stops with :class:`SweepCancelled` soon after ``cancel`` is set (a
:class:`threading.Event`, anything with ``is_set()``, or a callable returning
True) or :meth:`VariantSweep.cancel` is called from another thread.

Results are cached on disk (see :mod:`ramure.metrics.cache`), keyed by the grammar
text, constants, seed, n, beta, chosen constants, mode and samples, so a
second fit of the same sweep only reads one ``.npz``.

A variant whose derivation fails (e.g. a division by zero appears with the
changed constants) gets NaN metrics and ``failed_[i] = True``; it is left out
of the PCA and the picks.

>>> from ramure.lsys import LSystem
>>> sweep = VariantSweep(n=3, n_jobs=1, cache=False).fit(LSystem.from_file("grammars/honda_sympodial.lsys"))
>>> sweep.n_variants_, sweep.deltas_.shape, sweep.combination(0)["rule"]
(486, (486, 10), 0)
"""

from __future__ import annotations

import concurrent.futures as cf
import math
import multiprocessing
import os
import sys
import threading
import time

from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Self

import numpy as np

from ramure.lsys import LSystem
from ramure.lsys.engine.combination import combination
import ramure.grammars as grammar_files
from ramure.errors import RamureError, ValueRefused

from . import cache as _cache
from .estimator import ParamsMixin, check_n_jobs
from .plant import METRIC_NAMES, metric_deltas, metrics_from_arrays
from .shape import SHAPE_METRIC_NAMES, shape_deltas, shape_from_arrays
from .variants import describe_variant, distinct_variants, rule_constant_names, variant_design

if TYPE_CHECKING:
    from distributed import Client

    from ramure.lsys import Derivation


class SweepCancelled(RamureError):
    """The sweep was cancelled before it finished (nothing is cached)."""


def as_lsystem(grammar: LSystem | str | os.PathLike) -> LSystem:
    """Accept an :class:`~ramure.lsys.LSystem` or the path of an ``.lsys`` file."""
    if isinstance(grammar, LSystem):
        return grammar
    if isinstance(grammar, (str, os.PathLike)):
        path = grammar_files.resolve(grammar)
        if not path.is_file():
            raise ValueRefused(f"{path}: no such grammar file")
        return LSystem.from_file(path)
    raise ValueRefused(f"expected an LSystem or a grammar file path, not {type(grammar).__name__}")


# -- worker side ----------------------------------------------------------------
_PARSED: dict[tuple[str, str | None], LSystem] = {}


def _parsed(text, filename=None):
    """The grammar parsed once per process; ``filename`` lets ``#include``/``#surface`` files
    named relative to the grammar's folder be found from any working directory."""
    ls = _PARSED.get((text, filename))
    if ls is None:
        if len(_PARSED) > 8:
            _PARSED.clear()
        ls = _PARSED[text, filename] = LSystem.from_text(text, filename)
    return ls


def _filename(ls):
    name = getattr(ls.grammar, "filename", None)
    return None if name is None else str(name)


_WIDTH = len(METRIC_NAMES) + len(SHAPE_METRIC_NAMES)


def measure(
    lsystem: LSystem, n: int | None, seed: int, constants: Mapping[str, float] | None = None, params: dict | None = None
) -> np.ndarray:
    """Derive one plant and return its ten metrics then its five shape metrics (15,)."""
    sk = lsystem.derive(n=n, seed=seed, constants=constants, params=params).skeleton()
    return np.concatenate(
        [
            metrics_from_arrays(sk.start, sk.end, sk.base_radius, sk.top_radius),
            shape_from_arrays(sk.start, sk.end, sk.parent, sk.order),
        ]
    )


def evaluate_variants(
    text: str,
    constants: Mapping[str, float],
    n: int,
    seed: int,
    names: Sequence[str],
    rules: np.ndarray,
    values: np.ndarray,
    filename: str | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Metrics (c,15: ten metrics, five shape metrics) and failure flags (c,) of a chunk of
    variants — one worker task.

    Module-level and given plain data only, so it pickles for process pools
    and Dask workers alike; the grammar text is parsed once per worker
    (``filename``: the grammar file's path, for files it names relative to itself).
    """
    ls = _parsed(text, filename)
    out = np.full((len(rules), _WIDTH), np.nan)
    failed = np.zeros(len(rules), bool)
    for i, (rule, vals) in enumerate(zip(np.asarray(rules).tolist(), np.asarray(values).tolist())):
        try:
            # rule -1: an axiom literal (ramure.lsys.language.hidden), read when the plant is derived again
            out[i] = measure(ls, n, seed, constants, combination(None if rule < 0 else rule, dict(zip(names, vals))))
        except (RamureError, ArithmeticError, ValueError, MemoryError):
            failed[i] = True
    return out, failed


def _matches(stored, design):
    """A cache entry is used only if it holds exactly this design's variants."""
    try:
        return (
            stored is not None
            and stored["metrics"].shape == (len(design), _WIDTH)
            and np.array_equal(stored["rules"], design.rules)
            and np.array_equal(stored["values"], design.values)
        )
    except KeyError:
        return False


# -- the sweep ------------------------------------------------------------------
class VariantSweep(ParamsMixin):
    """All ``{k(1-beta), k, k(1+beta)}`` variants of a grammar, one rule at a time, measured.

    Parameters (stored as given; checked by :meth:`fit`):

    n, seed
        derivation steps (default: the grammar's ``n:``) and random seed.
    beta
        relative variation, in (0, 1); default 0.1 (+-10 %).
    constants
        names of the constants to vary (list or ``"r1,r2"``); default all non-zero ones.
    mode, n_samples
        ``"grid"`` (3^m per rule), or ``"lhs"`` / ``"sobol"`` with ``n_samples`` per rule.
    n_jobs
        worker processes, as in scikit-learn: None or 1 runs in this process, -1 uses
        every core, -2 all but one, ...; a bool is refused.
    chunk_size
        variants per task (default: about 8 tasks per worker, between 8 and 50).
    cache, cache_dir
        read/write the on-disk cache (``cache_dir`` default ``$RAMURE_CACHE`` or ``~/.cache/ramure``).
    scheduler, connect_timeout
        a Dask scheduler address (``"tcp://host:port"``) or a ``distributed.Client``;
        seconds to wait when connecting to an address (default 10).
    wide
        a larger step (e.g. 0.25 for +-25 %) added one constant at a time, per rule, to the
        grid (None: none); see :func:`ramure.metrics.variants.variant_design`.
    hidden
        also vary the grammar's hidden constants (:mod:`ramure.lsys.language.hidden`): its numeric
        literals and rule probabilities, one at a time (and the literals one rule writes alike,
        together), at ``+-beta`` and ``+-wide``; a grammar without ``#define`` is then swept too.
        Default False (the thesis's variants; the PCA cloud of an exploration stays as it was).
    mp_context
        multiprocessing start method for the local pool (default ``"fork"`` on Linux;
        a GUI running the sweep from a background thread should pass ``"forkserver"``,
        since forking a process with running threads is unsafe).

    Fitted attributes: ``names_`` (chosen constants), ``design_``
    (:class:`~ramure.metrics.variants.VariantDesign`), ``rules_`` (N,), ``values_`` (N,m),
    ``metrics_`` (N,10), ``base_metrics_`` (10,), ``deltas_`` (N,10), ``failed_`` (N,),
    ``shape_metrics_`` (N,5), ``base_shape_metrics_`` (5,), ``shape_deltas_`` (N,5) (the
    :mod:`ramure.metrics.shape` metrics, for qualifiers; the PCA uses the ten only),
    ``changes_`` (N,) (the variant changes a constant its rule reads: not the base plant),
    ``n_variants_``, ``n_derived_`` (derivations run; 0 from the cache), ``n_rules_``, ``n_``,
    ``hidden_`` (the hidden constants varied: ``{key: Hidden}``),
    ``grammar_text_``, ``grammar_file_`` (None for text), ``base_constants_``,
    ``seconds_``, ``from_cache_``, ``cache_path_``.
    """

    def __init__(
        self,
        n: int | None = None,
        seed: int = 0,
        beta: float = 0.1,
        constants: str | Iterable[str] | None = None,
        mode: str = "grid",
        n_samples: int | None = None,
        n_jobs: int | None = None,
        chunk_size: int | None = None,
        cache: bool = True,
        cache_dir: str | os.PathLike | None = None,
        scheduler: str | Client | None = None,
        mp_context: str | None = None,
        connect_timeout: float = 10.0,
        wide: float | None = None,
        hidden: bool = False,
    ) -> None:
        self.n = n
        self.seed = seed
        self.beta = beta
        self.constants = constants
        self.mode = mode
        self.n_samples = n_samples
        self.n_jobs = n_jobs
        self.chunk_size = chunk_size
        self.cache = cache
        self.cache_dir = cache_dir
        self.scheduler = scheduler
        self.mp_context = mp_context
        self.connect_timeout = connect_timeout
        self.wide = wide
        self.hidden = hidden

    @property
    def _event(self):
        """The cancel flag, created on first use (the constructor stores parameters only)."""
        event = self.__dict__.get("_cancel_event")
        if event is None:
            event = self.__dict__.setdefault("_cancel_event", threading.Event())
        return event

    # -- control -----------------------------------------------------------
    def cancel(self) -> None:
        """Ask a running :meth:`fit` (in another thread) to stop; it raises :class:`SweepCancelled`."""
        self._event.set()

    def _cancelled(self, cancel):
        if self._event.is_set():
            return True
        if cancel is None:
            return False
        return bool(cancel.is_set() if hasattr(cancel, "is_set") else cancel())

    # -- validation --------------------------------------------------------
    def _check(self, ls):
        n = ls.n if self.n is None else self.n
        if isinstance(n, bool) or int(n) != n or n < 0:
            raise ValueRefused(f"n must be a non-negative integer, not {self.n!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)):
            raise ValueRefused(f"seed must be an integer, not {self.seed!r}")
        jobs = check_n_jobs(self.n_jobs)
        if self.chunk_size is not None and (int(self.chunk_size) != self.chunk_size or self.chunk_size < 1):
            raise ValueRefused(f"chunk_size must be a positive integer, not {self.chunk_size!r}")
        return int(n), jobs

    def _key_payload(self, ls, n, design):
        return {
            "grammar": ls.text,
            "constants": {k: float(v) for k, v in ls.constants.items()},
            "seed": int(self.seed),
            "n": n,
            "beta": design.beta,
            "names": list(design.names),
            "mode": design.mode,
            "n_samples": self.n_samples,
            "wide": self.wide,
            "hidden": bool(self.hidden),
        }

    # -- fitting -----------------------------------------------------------
    def fit(
        self,
        grammar: LSystem | str | os.PathLike,
        progress: Callable[[int, int], None] | None = None,
        cancel: threading.Event | Callable[[], bool] | None = None,
    ) -> Self:
        """Derive and measure every variant of ``grammar`` (an LSystem or a file path)."""
        t0 = time.perf_counter()
        self._event.clear()
        ls = as_lsystem(grammar)
        n, jobs = self._check(ls)
        if not isinstance(self.hidden, (bool, np.bool_)):
            raise ValueRefused(f"hidden must be True or False, not {self.hidden!r}")
        knobs = {k: (h.value, h.rule) for k, h in ls.hidden.items()} if self.hidden else None
        design = variant_design(
            ls.constants, len(ls.grammar.rules), self.constants, self.beta, self.mode, self.n_samples, self.seed, self.wide, knobs
        )
        base_constants = dict(ls.constants)
        path = None
        stored = None
        if self.cache:
            path = _cache.cache_path(_cache.cache_key(self._key_payload(ls, n, design)), self.cache_dir)
            stored = _cache.load(path)
        if stored is not None and _matches(stored, design):
            metrics, failed, base = stored["metrics"], stored["failed"], stored["base_metrics"]
            self.from_cache_ = True
            self.n_derived_ = 0
            if progress is not None:
                progress(len(design), len(design))
        else:
            base = measure(ls, n, self.seed, base_constants)
            metrics, failed = self._run(ls, base_constants, n, design, base, jobs, progress, cancel)
            self.from_cache_ = False
            if path is not None:
                _cache.save(path, metrics=metrics, failed=failed, base_metrics=base, rules=design.rules, values=design.values)
        self.grammar_text_ = ls.text
        self.grammar_file_ = _filename(ls)
        self.base_constants_ = base_constants
        self.n_ = n
        self.n_rules_ = len(ls.grammar.rules)
        self.rule_names_ = [str(r.pred) for r in ls.grammar.rules]
        self.hidden_ = {k: ls.hidden[k] for k in design.hidden}
        self.design_ = design
        self.names_ = design.names
        self.rules_ = design.rules
        self.values_ = design.values
        k = len(METRIC_NAMES)
        self.metrics_ = metrics[:, :k]
        self.shape_metrics_ = metrics[:, k:]
        self.failed_ = failed.astype(bool)
        self.base_metrics_ = base[:k]
        self.base_shape_metrics_ = base[k:]
        self.deltas_ = metric_deltas(self.metrics_, self.base_metrics_)
        self.shape_deltas_ = shape_deltas(self.shape_metrics_, self.base_shape_metrics_)
        reps, inverse = distinct_variants(design, rule_constant_names(ls))
        self.changes_ = inverse >= 0
        self.n_variants_ = len(design)
        self.cache_path_ = path
        self.seconds_ = time.perf_counter() - t0
        return self

    def _chunks(self, total, jobs):
        size = self.chunk_size or min(50, max(8, math.ceil(total / (jobs * 8))))
        return [(i, min(i + size, total)) for i in range(0, total, size)]

    def _run(self, ls, constants, n, design, base, jobs, progress, cancel):
        reps, inverse = distinct_variants(design, rule_constant_names(ls))
        total = len(reps)
        rep_metrics = np.full((total, _WIDTH), np.nan)
        rep_failed = np.zeros(total, bool)
        chunks = self._chunks(total, jobs)
        args = [
            (
                ls.text,
                constants,
                n,
                int(self.seed),
                design.names,
                design.rules[reps[a:b]],
                design.values[reps[a:b]],
                _filename(ls),
            )
            for a, b in chunks
        ]
        done = 0

        def store(k, result) -> None:
            nonlocal done
            a, b = chunks[k]
            rep_metrics[a:b], rep_failed[a:b] = result
            done += b - a
            if progress is not None:
                progress(done, total)

        if progress is not None:
            progress(0, total)
        if self.scheduler is not None:
            self._run_dask(args, store, cancel)
        elif jobs == 1 or len(chunks) <= 1:
            for k, task in enumerate(args):
                if self._cancelled(cancel):
                    raise SweepCancelled("the sweep was cancelled")
                store(k, evaluate_variants(*task))
        else:
            self._run_pool(args, jobs, store, cancel)
        self.n_derived_ = total
        metrics = np.where((inverse < 0)[:, None], base, rep_metrics[np.maximum(inverse, 0)])
        failed = np.where(inverse < 0, False, rep_failed[np.maximum(inverse, 0)])
        return metrics, failed

    def _context(self):
        method = self.mp_context
        if method is None:
            method = "fork" if sys.platform.startswith("linux") else "spawn"
        return multiprocessing.get_context(method)

    def _run_pool(self, args, jobs, store, cancel):
        pool = cf.ProcessPoolExecutor(max_workers=min(jobs, len(args)), mp_context=self._context())
        try:
            pending = {pool.submit(evaluate_variants, *task): k for k, task in enumerate(args)}
            while pending:
                finished, _ = cf.wait(pending, timeout=0.1, return_when=cf.FIRST_COMPLETED)
                for fut in finished:
                    store(pending.pop(fut), fut.result())
                if pending and self._cancelled(cancel):
                    raise SweepCancelled("the sweep was cancelled")
        finally:
            pool.shutdown(wait=True, cancel_futures=True)

    def _run_dask(self, args, store, cancel):
        try:
            from dask.distributed import Client, as_completed
        except ImportError:
            raise RamureError("running on a Dask cluster needs Dask: pip install 'ramure[dask]'") from None
        own = isinstance(self.scheduler, str)
        if isinstance(self.scheduler, str):
            try:
                client = Client(self.scheduler, timeout=f"{float(self.connect_timeout)}s")
            except (OSError, TimeoutError) as exc:
                raise RamureError(f"cannot reach the Dask scheduler at {self.scheduler} ({exc})") from None
        else:
            assert self.scheduler is not None  # only called with a scheduler (see fit)
            client = self.scheduler
        futures = []
        try:
            futures = [client.submit(evaluate_variants, *task, pure=False) for task in args]
            index = {f.key: k for k, f in enumerate(futures)}
            for fut in as_completed(futures):
                store(index[fut.key], fut.result())
                if self._cancelled(cancel):
                    raise SweepCancelled("the sweep was cancelled")
        finally:
            if futures:
                client.cancel(futures)
            if own:
                client.close()

    # -- queries -----------------------------------------------------------
    def _fitted(self):
        if not hasattr(self, "deltas_"):
            raise ValueRefused("this sweep is not fitted yet: call fit(grammar) first")

    def combination(self, i: int) -> dict:
        """The parameter combination ``{"rule": int, "constants": {...}}`` of variant ``i``."""
        self._fitted()
        if not 0 <= int(i) < self.n_variants_:
            raise ValueRefused(f"variant {i} is out of range 0..{self.n_variants_ - 1}")
        return self.design_.combination(int(i))

    def describe(self, i: int) -> dict:
        """What variant ``i`` changed against the grammar: ``{"rule", "predecessor", "constants":
        {name: [before, after]}, "text"}`` (see :func:`ramure.metrics.variants.describe_variant`)."""
        self.combination(i)  # validates i
        return describe_variant(
            self.design_, int(i), self.base_constants_, getattr(self, "rule_names_", ()), getattr(self, "hidden_", {})
        )

    def derive(self, i: int, n: int | None = None) -> Derivation:
        """Derive variant ``i`` again (e.g. to render it); ``n`` defaults to the sweep's."""
        self._fitted()
        ls = _parsed(self.grammar_text_, getattr(self, "grammar_file_", None))
        return ls.derive(
            n=self.n_ if n is None else n, seed=self.seed, constants=self.base_constants_, params=self.combination(i)
        )
