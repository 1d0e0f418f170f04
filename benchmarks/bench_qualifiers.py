"""Qualifiers on every grammar (issue 35): each word's move on its own metric and on the others.

For every shipped grammar with ``#define`` constants and every grammar in ``tests/data``, the
sweep (+-10 %, plus +-25 % one constant at a time, plus the hidden constants: literals, axiom
numbers and rule probabilities, :mod:`ramure.lsys.language.hidden`) is fitted and each of the 22 qualifiers is
applied to the whole plant in a fresh session; the plant is then measured again, independently
of the qualifier machinery, and each qualifier's defining metrics
(:mod:`ramure.metrics.definitions`) compared before and after.  The collision matrix of the
vocabulary's regions gives the pairs the data cannot separate (synonyms for that plant), and
on the conifer and the shrub 3 tips check that no qualifier replaces the whole plant; on
Honda branches, dense, sparse and bushy (which need segments added or removed) are counted.

The report is written to ``docs/qualifier_report.md`` (linked from the docs); the JSON line
gives the refusal counts, the worst inversion left (the smallest signed move of a defining
metric among applied results: negative would be an inversion) and the seconds.

Run it alone: ``python benchmarks/run.py bench_qualifiers`` (a few minutes on 2 cores).
"""

from __future__ import annotations

import pathlib
import time

import numpy as np

from ramure.errors import RamureError
from ramure.io import write_text
from ramure.lsys import LSystem
from ramure.lsys.regeneration.regen import Session
from ramure.metrics import VariantSweep, plant_metrics, plant_shape
from ramure.metrics.apply import apply_qualifier
from ramure.metrics.definitions import DEFINITIONS, LABELS, metric_value
from ramure.metrics.qualifiers import VOCABULARY, synonyms, vocabulary_regions
import ramure.grammars as grammar_files

ROOT = pathlib.Path(__file__).resolve().parents[1]
REPORT = ROOT / "docs" / "qualifier_report.md"
#: Largest base plant measured (segments): n is lowered until the plant fits.
MAX_SEGMENTS = 6000
SHOWN = ("height", "crown_width", "box_volume", "branch_count", "branch_density", "sphericity", "mean_radius", "branch_angle")


def _grammars():
    shipped = [(name, grammar_files.resolve(name)) for name in grammar_files.names()]
    tests = [("tests/data/conifer", ROOT / "tests" / "data" / "conifer.lsys")]
    tests += [(f"tests/data/grammars/{p.stem}", p) for p in sorted((ROOT / "tests" / "data" / "grammars").glob("*.lsys"))]
    return shipped + tests


def _values(session):
    sk = session.derivation.skeleton()
    return np.concatenate([np.array(plant_metrics(sk), float), np.array(plant_shape(sk), float)])


def _n(ls):
    n = ls.n
    while n > 1 and int(plant_metrics(ls.derive(n=n).skeleton()).branch_count) > MAX_SEGMENTS:
        n -= 1
    return n


def _pct(a, b):
    return 100.0 * (a - b) / abs(b) if b else (0.0 if a == b else float("inf"))


def _row(q, out, before, after):
    terms = DEFINITIONS.get(q)
    own = ""
    margin = None
    if terms is not None:
        parts = []
        for m, sign in terms.terms():
            b, a = float(metric_value(m, before)), float(metric_value(m, after))
            parts.append(f"{m} {b:.4g} → {a:.4g}")
            if b == 0 and a == 0:  # a ratio with no denominator (no crown): undefined, not a move
                continue
            move = sign * _pct(a, b)
            margin = move if margin is None else min(margin, move)
        own = "; ".join(parts)
    others = ", ".join(
        f"{m} {_pct(float(metric_value(m, after)), float(metric_value(m, before))):+.0f} %"
        for m in SHOWN
        if terms is None or m not in dict(terms.terms())
    )
    return own, others, margin


def grammar_report(name, path):
    """``(markdown lines, figures)`` for one grammar."""
    ls = LSystem.from_file(path)
    n = _n(ls)
    try:
        sweep = VariantSweep(n=n, n_jobs=2, wide=0.25, hidden=True).fit(ls)
    except RamureError as exc:
        return [f"### {name}", "", f"Not swept: {exc}.", ""], {"grammar": name, "swept": False}
    lines = [
        f"### {name}",
        "",
        f"n = {n}, {int(sweep.base_metrics_[5])} segments, {sweep.n_variants_} variants ({', '.join(sweep.names_)}).",
        "",
        "| qualifier | result | what changed | own metric before → after | others |",
        "|---|---|---|---|---|",
    ]
    refused, worst = [], (float("inf"), None)
    for q in VOCABULARY:
        session = Session(ls, n=n)
        before = _values(session)
        out = apply_qualifier(session, q, sweep, tries=3)
        after = _values(session)
        own, others, margin = _row(q, out, before, after)
        if q == "normal":
            verdict = "closest variant"
        elif out.improved:
            verdict = "applied" if out.dominant else f"applied ({out.rival} moved more)"
            if margin is not None and margin < worst[0]:
                worst = (margin, q)
        else:
            verdict = "**refused**"
            refused.append((q, out.reason))
        changed = (out.changed or {}).get("text", "") if out.improved or q == "normal" else ""
        lines.append(f"| {q} | {verdict} | {changed} | {own} | {others} |")
    lines.append("")
    if refused:
        lines += [f"Refused ({len(refused)}):", ""] + [f"- **{q}**: {why}" for q, why in refused] + [""]
    pairs = synonyms(vocabulary_regions(sweep))
    if pairs:
        said = ", ".join(f"{a} ~ {b} ({s:.0f} %)" for a, b, s in pairs)
        lines += [f"Regions that do not separate (synonyms for this plant): {said}.", ""]
    figures = {
        "grammar": name,
        "swept": True,
        "refused": len(refused),
        "worst_margin": worst[0],
        "worst_qualifier": worst[1],
        "synonyms": len(pairs),
    }
    return lines, figures


def _tips_whole(path):
    """How many of the 22 qualifiers, on 3 tips, replaced the whole plant (issue 35: 8 and 10)."""
    ls = LSystem.from_file(path)
    sweep = VariantSweep(n_jobs=2, wide=0.25, hidden=True).fit(ls)
    whole = 0
    for q in VOCABULARY:
        session = Session(ls)
        tree = session.tree
        f = session.leaves_with_symbol("F")
        tips = f[tree.step[f] == session.n]
        tips = tips[len(tips) // 2 : len(tips) // 2 + 3].tolist()
        out = apply_qualifier(session, q, sweep, selection=tips, tries=2)
        whole += bool((tree.parent[out.roots] < 0).any()) or session.n != ls.n
    return whole


def _branch_words(grammar="honda_sympodial", count=8):
    """``{word: applied of count}`` for dense, sparse and bushy on random branches (issue 35 §3)."""
    sweep = VariantSweep(n=6, n_jobs=2, wide=0.25, hidden=True).fit(grammar)
    rng = np.random.default_rng(3)
    out = {}
    for q in ("dense", "sparse", "bushy"):
        applied = 0
        for _ in range(count):
            session = Session(grammar, n=6)
            tree = session.tree
            f = set(session.leaves_with_symbol("F").tolist())
            nodes = np.flatnonzero(tree.alive & (tree.child_count > 0) & (tree.depth >= 1))
            leaves: list[int] = []
            while len(leaves) < 2:
                leaves = [x for x in tree.leaves_under(int(rng.choice(nodes))).tolist() if x in f]
            applied += apply_qualifier(session, q, sweep, selection=leaves, tries=3).improved
        out[q] = applied
    return out


def bench_qualifier_grid():
    t0 = time.perf_counter()
    body, figures = [], []
    for name, path in _grammars():
        lines, fig = grammar_report(name, path)
        body += lines
        figures.append(fig)
    swept = [f for f in figures if f["swept"]]
    tips = {
        "conifer": _tips_whole(ROOT / "tests" / "data" / "conifer.lsys"),
        "shrub": _tips_whole(ROOT / "tests" / "data" / "grammars" / "shrub.lsys"),
    }
    branches = {g: _branch_words(g) for g in ("honda_sympodial", "honda_monopodial")}
    worst = min(swept, key=lambda f: f["worst_margin"])
    head = [
        "# Qualifier report",
        "",
        "Generated by `python benchmarks/run.py bench_qualifiers` (issue 35). Each qualifier is applied to the",
        "whole plant of each grammar in a fresh session; the plant is measured again afterwards. *Own metric*:",
        "the qualifier's definition (see [Qualifiers](qualifiers.md)); *others*: the relative change of",
        f"the other shape and size metrics. Metrics: {', '.join(f'`{m}` ({LABELS[m]})' for m in SHOWN)}.",
        "",
        "## Summary",
        "",
        "| grammar | refused of 22 | smallest own move (%) | synonym pairs |",
        "|---|---|---|---|",
    ]
    for f in figures:
        if f["swept"]:
            move = f"{f['worst_margin']:.3g} ({f['worst_qualifier']})"
            head.append(f"| {f['grammar']} | {f['refused']} | {move} | {f['synonyms']} |")
        else:
            head.append(f"| {f['grammar']} | not swept (no number to vary) | | |")
    head += [
        "",
        f"3 tips selected: qualifiers that replaced the whole plant — conifer {tips['conifer']} of 22, "
        f"shrub {tips['shrub']} of 22 (issue 35 reported 8 and 10).",
        "",
        "On a selection, dense, sparse and bushy may regrow the selected part one derivation step more",
        "or less (the rest of the plant unchanged). Applied on 8 random branches each (n = 6): "
        + "; ".join(f"{g} " + ", ".join(f"{q} {k} of 8" for q, k in w.items()) for g, w in branches.items())
        + " (before: refused on every branch).",
        "",
        "Worst inversion left: smallest signed move of a defining metric among applied results is "
        f"{worst['worst_margin']:.3g} % ({worst['worst_qualifier']} on {worst['grammar']}); "
        "a negative value would be an inversion.",
        "",
        "## Per grammar",
        "",
    ]
    write_text(REPORT, "\n".join(head + body) + "\n")
    refused = {f["grammar"]: f["refused"] for f in swept}
    return {
        "seconds": time.perf_counter() - t0,
        "grammars": len(figures),
        "swept": len(swept),
        "refused": refused,
        "max_refused": max(refused.values()),
        "worst_inversion_pct": worst["worst_margin"],
        "worst_inversion": f"{worst['worst_qualifier']} on {worst['grammar']}",
        "tips_whole_plant": tips,
        "branch_words": branches,
        "report": str(REPORT.relative_to(ROOT)),
        "ok": worst["worst_margin"] > 0 and all(v == 0 for v in tips.values()),
    }
