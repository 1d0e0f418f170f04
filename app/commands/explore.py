"""``ramure explore | metrics | qualify``: variant exploration, plant metrics, qualifier edits.

::

    ramure explore grammars/honda_sympodial.lsys -n 7 -o out/honda --json
    ramure metrics grammars/honda_sympodial.lsys --select 12,15,20-23 --tight --json
    ramure qualify grammars/honda_sympodial.lsys --qualifier dense --select 12,15,20-23 -o session.json

``explore`` writes ``variants.csv``, ``pca.json``, ``picks.json``,
``thumbs/pick_XX.png`` and ``contact_sheet.png`` (see :mod:`ramure.metrics.exploration`);
with ``--json`` it prints one summary object (variant count, the 27 picks
with their parameter combinations, matching distances, seconds).
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
import time
from typing import TYPE_CHECKING, Any

from ramure.app.cli import UserError
from ramure.app.commands.plant import add_grammar_options, parse_sets, parse_size
from ramure.app.commands.regen import parse_ids
from ramure.lsys import LSystem
from ramure.errors import RamureError

if TYPE_CHECKING:
    from ramure.metrics.qualifiers import QualifierRegions
    from ramure.metrics.exploration import Exploration
    from ramure.app.cli import Subparsers


def _size(text):
    return parse_size(text, "--thumb-size")


def _load(args):
    ls = LSystem.from_file(args.file)
    ls.constants.update(parse_sets(args.set, ls.constants))
    if args.n is not None and args.n < 0:
        raise RamureError(f"-n must be >= 0, not {args.n}")
    return ls


def _ids(text, option):
    """``"12,15,20-23"`` -> ids, refusing bad syntax as a user error (exit 2, no traceback)."""
    try:
        return parse_ids(text)
    except UserError as exc:
        raise RamureError(str(exc).replace("--select", option)) from None


def _check_leaves(ids, leaves):
    """Refuse ids that are not leaves of the current string (leaves drawing nothing are fine)."""
    unknown = sorted(set(ids) - set(leaves.tolist()))
    if unknown:
        raise RamureError(
            f"--select: {', '.join(map(str, unknown[:5]))}"
            f"{' ...' if len(unknown) > 5 else ''} not leaf id(s) of this plant "
            "(see 'ramure leaves FILE' for the ids)"
        )


def _progress_bar(enabled, desc):
    """A ``progress(done, total)`` callback drawing a tqdm bar on stderr, and a closer."""
    if not enabled:
        return None, lambda: None
    from tqdm import tqdm

    state: dict[str, Any] = {}

    def progress(done, total):
        bar = state.get("bar")
        if bar is None:
            bar = state["bar"] = tqdm(total=total, desc=desc, unit="variant", file=sys.stderr, disable=None, leave=False)
        bar.update(done - bar.n)

    def close():
        if "bar" in state:
            state["bar"].close()

    return progress, close


def _add_sweep_options(p):
    p.add_argument("--beta", type=float, default=0.1, help="relative variation of each constant (default 0.1)")
    p.add_argument("--constants", default=None, metavar="K1,K2", help="constants to vary (default: every non-zero #define)")
    p.add_argument(
        "--mode",
        choices=["grid", "lhs", "sobol"],
        default="grid",
        help="grid: all 3^m combinations per rule; lhs/sobol: --samples per rule",
    )
    p.add_argument("--samples", type=int, default=None, help="samples per rule for --mode lhs/sobol")
    p.add_argument(
        "--wide", type=float, default=None, metavar="FRACTION", help="also move each constant alone by +-FRACTION (e.g. 0.25)"
    )
    p.add_argument(
        "--hidden",
        action="store_true",
        help="also vary the numbers the grammar writes without a name: literals, axiom numbers, rule probabilities",
    )
    p.add_argument("--jobs", type=int, default=-1, help="worker processes (default -1: every core; 1 runs in this process)")
    p.add_argument(
        "--scheduler", default=None, metavar="tcp://HOST:PORT", help="run the sweep on a Dask cluster (needs ramure[dask])"
    )
    p.add_argument("--no-cache", action="store_true", help="do not read or write the sweep cache")
    p.add_argument("--cache-dir", default=None, help="cache directory (default $RAMURE_CACHE or ~/.cache/ramure)")


def _sweep_kwargs(args):
    return dict(
        n=args.n,
        seed=args.seed,
        beta=args.beta,
        constants=args.constants,
        mode=args.mode,
        n_samples=args.samples,
        n_jobs=args.jobs,
        cache=not args.no_cache,
        cache_dir=args.cache_dir,
        scheduler=args.scheduler,
        wide=args.wide,
        hidden=args.hidden,
    )


# -- explore ----------------------------------------------------------------------
def run_explore(args: argparse.Namespace) -> int:
    """``ramure explore``: sweep the grammar's constants (the sweep options), derive every variant, measure it,
    place it in the PCA of its metrics and write the exploration (table, thumbnails, JSON) to the ``-o``
    folder; returns 0.
    """
    from ramure.metrics.exploration import explore, write_exploration

    t0 = time.perf_counter()
    if pathlib.Path(args.output).exists() and not pathlib.Path(args.output).is_dir():
        raise RamureError(f"-o {args.output}: exists and is not a directory")
    ls = _load(args)
    size = _size(args.thumb_size)
    progress, close = _progress_bar(not args.json or sys.stderr.isatty(), "variants")
    try:
        exp = explore(ls, standardize=args.standardize, match=args.match, progress=progress, **_sweep_kwargs(args))
    finally:
        close()
    exp.name = args.grammar_name or pathlib.Path(args.file).stem
    out = pathlib.Path(args.output)
    images = None
    if not args.no_thumbnails:
        from ramure.app.thumbnails import contact_sheet, render_picks

        images = render_picks(exp, out, size=size)
        contact_sheet(
            [out / p for p in images],
            range(1, 28),
            out / "contact_sheet.png",
            title=f"{exp.name}: 27 picks (rows = PC1 low, mid, high)",
        )
    paths = write_exploration(exp, out, images)
    if args.store:
        from ramure.metrics.store import QualifierStore

        with QualifierStore(args.store) as store:
            store.write_default(exp)
    summary = exp.summary(images)
    summary["seconds"] = round(time.perf_counter() - t0, 4)
    summary["sweep_seconds"] = round(exp.sweep.seconds_, 4)
    summary["output"] = str(out)
    if args.json:
        print(json.dumps(summary))
        return 0
    m = exp.matching
    print(
        f"{summary['variants']} variants ({summary['failed']} failed) of {exp.name} in "
        f"{summary['seconds']:.2f} s{' (from cache)' if summary['from_cache'] else ''}"
    )
    ratio = ", ".join(f"{r:.1%}" for r in exp.pca.explained_variance_ratio_)
    print(f"PCA explained variance: {ratio}")
    print(
        f"matching distance: sequential {m['sequential']:.4g}, greedy {m['greedy']:.4g}, "
        f"optimal {m['optimal']:.4g} (using {exp.picks.method})"
    )
    print(
        f"wrote {', '.join(p.name for p in paths.values())}"
        + ("" if images is None else ", thumbs/, contact_sheet.png")
        + f" to {out}"
    )
    return 0


# -- metrics ----------------------------------------------------------------------
def run_metrics(args: argparse.Namespace) -> int:
    """``ramure metrics``: derive the plant and print its metrics and oriented bounding box, of the whole plant
    or of the leaves ``--select`` / segments ``--segments`` given; returns 0.
    """
    from ramure.metrics.plant import plant_metrics, plant_obb

    t0 = time.perf_counter()
    ls = _load(args)
    d = ls.derive(n=args.n, seed=args.seed)
    sk = d.skeleton()
    leaf_ids = _ids(args.select, "--select") if args.select else None
    segments = _ids(args.segments, "--segments") if args.segments else None
    if leaf_ids is not None:
        _check_leaves(leaf_ids, d.leaves)
    m = plant_metrics(sk, leaf_ids, segments)
    box = plant_obb(sk, leaf_ids, segments)
    mask_count = m.branch_count
    record = {
        "file": args.file,
        "n": ls.n if args.n is None else args.n,
        "segments": len(sk),
        "selected_segments": mask_count,
        "metrics": m.to_dict(),
        "obb": box.to_dict(),
    }
    if args.tight:
        tight = plant_obb(sk, leaf_ids, segments, tight=True)
        record["tight_obb"] = {
            **tight.to_dict(),
            "reduction_percent": 100.0 * (1 - tight.volume / box.volume) if box.volume > 0 else 0.0,
        }
        record["tight_metrics"] = plant_metrics(sk, leaf_ids, segments, tight=True).to_dict()
    record["seconds"] = round(time.perf_counter() - t0, 6)
    if args.json:
        print(json.dumps(record))
        return 0
    for k, v in m.to_dict().items():
        print(f"{k:15s} {v:.6g}")
    if args.tight:
        print(f"tight box volume {record['tight_obb']['volume']:.6g} ({record['tight_obb']['reduction_percent']:.1f} % smaller)")
    return 0


# -- qualify ----------------------------------------------------------------------
def run_qualify_list(args: argparse.Namespace) -> int:
    """``ramure qualify --list``: every qualifier, its French name and its metric direction."""
    from ramure.metrics.qualifiers import vocabulary_table

    table = vocabulary_table()
    if getattr(args, "words", None):  # a study's words, with their measured directions
        from ramure.metrics.words import describe_direction, read_words_file, word_label

        for name, entry in read_words_file(args.words).items():
            meaning = str(entry.get("meaning") or "a study's word")
            direction = describe_direction(entry["direction"], 3)
            table.append(dict(name=word_label(name), french="", direction=direction, meaning=meaning, antonym=None))
    if args.json:
        print(json.dumps(table))
        return 0
    for row in table:
        anto = f" (opposite: {row['antonym']})" if row["antonym"] else ""
        names = row["name"] + "/" + row["french"] if row["french"] else row["name"]
        print(f"{names:24s} {row['direction']:45s} {row['meaning']}{anto}")
    return 0


def run_qualify_matrix(args: argparse.Namespace, ls: LSystem, exp: Exploration, regions: QualifierRegions | None) -> int:
    """``ramure qualify --matrix FILE``: the qualifiers' collision matrix on this grammar."""
    from ramure.metrics.qualifiers import matrix_table, synonyms, vocabulary_regions

    source = "study" if regions is not None else "vocabulary"
    if regions is None:  # in the fifteen-metric space the qualifiers are defined in
        regions = vocabulary_regions(exp.sweep, trim=args.trim)
    from ramure.metrics.qualifiers import VOCABULARY

    missing = [q for q, v in VOCABULARY.items() if v.direction is not None and q not in regions.names_]
    if args.json:
        print(
            json.dumps(
                {
                    "grammar": exp.name,
                    "source": source,
                    "names": regions.names_,
                    "french": [VOCABULARY[n].french if n in VOCABULARY else n for n in regions.names_],
                    "collision_matrix": regions.collision_matrix_.round(4).tolist(),
                    "mean_collision": round(regions.mean_collision(), 4),
                    "without_region": missing,
                    "synonyms": [list(pair) for pair in synonyms(regions)],
                }
            )
        )
        return 0
    print(f"collision matrix of {exp.name} ({source} regions; row A, column B: % of A's points inside B's box)")
    if args.lang == "fr":  # the same matrix, rows and columns named in French
        import copy

        regions = copy.copy(regions)
        regions.names_ = [VOCABULARY[n].french if n in VOCABULARY else n for n in regions.names_]
    print(matrix_table(regions))
    if missing:
        print(f"no region (no variant moves them more than another qualifier): {', '.join(missing)}")
    return 0


def _save_directions(path, exp, regions):
    """Write this grammar's qualifier directions (refined by its study regions, if any) as JSON."""
    from ramure.io import write_text
    from ramure.metrics.qualifiers import QualifierModel

    model = QualifierModel(regions=regions).fit(exp.sweep, points=exp.points)
    doc = {"grammar": exp.name, **model.to_dict()}
    write_text(path, json.dumps(doc, indent=1))


def _load_directions(path):
    """``{qualifier: {metric: weight}}`` from a ``--save-directions`` file (or a bare mapping)."""
    from ramure.metrics.qualifiers import QUALIFIER_METRICS

    try:
        doc = json.loads(pathlib.Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise RamureError(f"--directions {path}: cannot read it ({exc.strerror})") from None
    except json.JSONDecodeError as exc:
        raise RamureError(f"--directions {path}: not JSON (line {exc.lineno}: {exc.msg})") from None
    directions = doc.get("directions", doc) if isinstance(doc, dict) else None
    ok = isinstance(directions, dict) and all(
        isinstance(w, dict)
        and w
        and all(m in QUALIFIER_METRICS and isinstance(v, (int, float)) and not isinstance(v, bool) for m, v in w.items())
        for w in directions.values()
    )
    if not ok:
        raise RamureError(
            f"--directions {path}: expected {{qualifier: {{metric: weight}}}} over the metrics {', '.join(QUALIFIER_METRICS)}"
        )
    return directions


def _describe(result):
    """One human line per own metric, then the verdict."""
    lines = []
    for metric, v in result.own.items():
        arrow = "up" if v["direction"] > 0 else "down"
        lines.append(f"  {metric}: {v['before']:.4g} -> {v['after']:.4g} (wanted {arrow})")
    verdict = "improved" if result.improved else "NOT improved"
    if result.improved and not result.dominant:
        verdict += f" (but {result.rival} moved more)"
    head = (
        f"{result.qualifier}: variant {result.variant} {json.dumps(result.params)} ({result.source}); "
        f"{verdict} after {result.tried} tr{'y' if result.tried == 1 else 'ies'}"
    )
    if result.climbed:
        head += f"; climbed {result.climbed} level{'s' if result.climbed > 1 else ''} (min ascension {result.min_ascend})"
    out = [head, *lines]
    if result.reason:
        out.append(f"  why: {result.reason}")
    if result.suggestion and not result.improved:
        out.append(f"  try: {result.suggestion}")
    return "\n".join(out)


def run_qualify(args: argparse.Namespace) -> int:
    """``ramure qualify``: apply a qualifier ("taller", "bushier"...) to the plant or to a selection (``--list``
    shows the vocabulary, ``--matrix`` and ``--save-directions`` the learnt directions), regrowing toward
    it, and print what changed; returns 0.
    """
    from ramure.lsys.regeneration.regen import Session
    from ramure.metrics.apply import apply_qualifier
    from ramure.metrics.exploration import explore
    from ramure.metrics.qualifiers import canonical_name, vocabulary_name
    from ramure.metrics.store import QualifierStore
    from ramure.metrics.words import read_words

    if args.list:
        return run_qualify_list(args)
    t0 = time.perf_counter()
    if args.file is None:
        raise RamureError("give a grammar FILE (or --list for the vocabulary)")
    if args.qualifier is None and not args.matrix and not args.save_directions:
        raise RamureError("give --qualifier NAME (see 'ramure qualify --list'), --matrix or --save-directions")
    if args.directions:
        _load_directions(args.directions)  # refuse a bad file before the sweep
    words = read_words(args.words) if args.words else {}
    if args.tries < 1:
        raise RamureError(f"--tries must be at least 1, not {args.tries}")
    if args.climb < 0:
        raise RamureError(f"--climb must be a whole number of levels >= 0, not {args.climb}")
    if not 0 <= args.trim < 1:
        raise RamureError(f"--trim is the share of points trimmed, in [0, 1), not {args.trim}")
    ls = LSystem.from_file(args.file)
    sets = parse_sets(args.set, ls.constants)
    ls.constants.update(sets)
    name = args.grammar_name or pathlib.Path(args.file).stem
    regions = None
    if args.store:
        with QualifierStore(args.store) as store:
            regions = store.regions(name, source=args.source, trim=args.trim)
    qualifier = None
    if args.qualifier is not None:
        qualifier = canonical_name(args.qualifier, args.lang)
        if regions is None or qualifier not in regions:
            vocabulary_name(args.qualifier, args.lang, extra=words)  # refuse unknown names before the sweep
    progress, close = _progress_bar(not args.json or sys.stderr.isatty(), "variants")
    try:
        exp = explore(ls, progress=progress, **_sweep_kwargs(args))
    finally:
        close()
    exp.name = name
    if args.save_directions:
        _save_directions(args.save_directions, exp, regions)
    if args.matrix:
        return run_qualify_matrix(args, ls, exp, regions)
    if qualifier is None:
        return 0
    session = Session(ls, n=args.n, seed=args.seed, filename=args.file)
    selection = _ids(args.select, "--select") if args.select else []
    _check_leaves(selection, session.tree.leaves)
    rho = args.rho / 100.0 if args.rho > 1 else args.rho
    directions = {**words, **(_load_directions(args.directions) if args.directions else {})} or None
    result = apply_qualifier(
        session,
        qualifier,
        exp.sweep,
        selection=selection,
        rho=rho,
        points=exp.points,
        regions=regions,
        tries=args.tries,
        max_climb=args.climb,
        directions=directions,
    )
    if args.output:
        session.save(args.output)
    record = {
        **result.to_dict(),
        "selection": selection,
        "modules": len(session.derivation),
        "variants": int(exp.sweep.n_variants_),
        "seconds": round(time.perf_counter() - t0, 4),
    }
    if args.output:
        record["session"] = args.output
    if args.json:
        print(json.dumps(record))
        return 0
    print(_describe(result))
    if args.output:
        print(f"wrote {args.output}")
    return 0


def register(sub: Subparsers) -> None:
    """Add ``explore`` (variant sweeps), ``metrics`` and ``qualify`` to the CLI's subcommands."""
    p = sub.add_parser("explore", help="sweep the constants' variants, PCA, 27 picks, thumbnails")
    add_grammar_options(p)
    _add_sweep_options(p)
    p.add_argument("--standardize", action="store_true", help="standardise each metric before the PCA")
    p.add_argument(
        "--match",
        choices=["optimal", "greedy", "sequential"],
        default="optimal",
        help="how variants are matched to the 27 interest points (default optimal)",
    )
    p.add_argument("--no-thumbnails", action="store_true", help="skip rendering thumbnails")
    p.add_argument("--thumb-size", default="240x240", help="thumbnail size WIDTHxHEIGHT")
    p.add_argument("--grammar-name", default=None, help="name recorded for the grammar (default: file stem)")
    p.add_argument(
        "--store", default=None, metavar="SQLITE", help="also write the default vocabulary's points into this qualifier store"
    )
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    p.set_defaults(func=run_explore)

    p = sub.add_parser("metrics", help="the ten metrics and OBB of a plant or a selection")
    add_grammar_options(p)
    p.add_argument("--select", default=None, metavar="LEAF_IDS", help="history leaf ids, e.g. 12,15,20-23")
    p.add_argument("--segments", default=None, metavar="IDS", help="segment indices, e.g. 0-9")
    p.add_argument("--tight", action="store_true", help="also report the refined (tighter) OBB")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=run_metrics)

    p = sub.add_parser(
        "qualify",
        help="regrow a selection (or the plant) toward a qualifier, e.g. dense; "
        "--list the vocabulary, --matrix the collision matrix",
    )
    add_grammar_options(p, file_optional=True)  # FILE is optional with --list
    _add_sweep_options(p)
    p.add_argument(
        "--qualifier", default=None, help="a qualifier in English or French, e.g. dense, tall/haut, upright/érigé (see --list)"
    )
    p.add_argument(
        "--lang",
        choices=["en", "fr"],
        default=None,
        help="read --qualifier as French first ('large' = wide) or English ('large' = big); "
        "fr also names --matrix's rows and columns in French",
    )
    p.add_argument(
        "--list", action="store_true", help="print every qualifier with its French name and metric direction, then exit"
    )
    p.add_argument(
        "--matrix",
        action="store_true",
        help="print the qualifiers' collision matrix on FILE (study regions with --store, else the default vocabulary's)",
    )
    p.add_argument(
        "--save-directions",
        default=None,
        metavar="JSON",
        help="write this grammar's qualifier directions (refined by --store regions) for --directions on another grammar",
    )
    p.add_argument(
        "--directions",
        default=None,
        metavar="JSON",
        help="qualifier directions learnt elsewhere (a --save-directions file): transfer a study to a grammar that has none",
    )
    p.add_argument(
        "--words",
        default=None,
        metavar="JSON",
        help="a vocabulary file of study words ('ramure study words'): its words are accepted as --qualifier",
    )
    p.add_argument("--select", default=None, metavar="LEAF_IDS", help="leaf ids (default: the whole plant)")
    p.add_argument("--rho", type=float, default=0.5, help="cut threshold in (0, 1] (or 0-100)")
    p.add_argument("--tries", type=int, default=5, help="candidate combinations to try per level (default 5)")
    p.add_argument(
        "--climb",
        type=int,
        default=0,
        metavar="LEVELS",
        help="on a selection, levels the qualifier may climb above the selection's cut when that part "
        "cannot move (default 0: only what a regrow of the selection changes)",
    )
    p.add_argument("--store", default=None, metavar="SQLITE", help="qualifier store with study regions")
    p.add_argument("--source", default="study:%", help="store rows to use (default 'study:%%')")
    p.add_argument("--trim", type=float, default=0.07, help="share of extreme points trimmed (default 0.07)")
    p.add_argument("--grammar-name", default=None, help="grammar name in the store (default: file stem)")
    p.add_argument("--json", action="store_true")
    p.add_argument("-o", "--output", default=None, help="save the edited session (JSON) here")
    p.set_defaults(func=run_qualify)
