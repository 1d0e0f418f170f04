"""The study report: one HTML page with heat maps, box plots and tables, plus CSVs.

:func:`analyze` computes every figure of the thesis' study chapter from a
:class:`~ramure.studies.data.StudyData`; :func:`write_report` writes them to a folder:

* ``index.html`` -- the page (figures are PNG files next to it);
* ``cooccurrence.png``, ``grouping.png``, ``ratings.png``, ``qualifiers.png``,
  ``collision.png`` (the qualifiers' collision matrix as a heat map);
* ``cooccurrence_<grammar>.csv`` and ``cooccurrence_all.csv`` (27 x 27);
* ``image_ratings_usefulness.tsv`` / ``..._difference.tsv`` -- rows = image
  points, columns = grammars: the layout ``ramure study anova`` reads back;
* ``grouping_stats.csv``, ``anova.csv`` (the thesis's tables, labelled: not an
  inference), ``qualifiers.csv``, ``qualifiers_unmatched.csv``;
* ``inference.csv`` and ``pairwise.csv`` (participants as the unit,
  :mod:`~ramure.studies.inference`), ``agreement.csv`` (adjusted Rand index per
  grammar), ``test_quality.csv`` (time on task and flags per test);
* ``dendrogram.png`` (co-occurrence ordered by clustering) and ``answers.png``
  (diverging bars of every Likert answer);
* ``summary.json`` (everything above as JSON).

Figures use matplotlib's object API on the Agg canvas, never pyplot, so the
report can be written from inside a Qt application.

>>> import tempfile, pathlib
>>> from ramure.studies.simulate import simulate_study
>>> out = pathlib.Path(tempfile.mkdtemp())
>>> data = simulate_study(participants=3, grammars=2)
>>> summary = write_report(data, out)
>>> (out / "index.html").is_file(), summary["tests"]
(True, 6)
"""

from __future__ import annotations

import csv
import html
import json
import math
import os
import pathlib
import re

import numpy as np

from ramure.io import open_atomic, write_text, write_with
from ramure.studies.agreement import cooccurrence_order, grouping_agreement, qualifier_agreement
from ramure.studies.analysis import MEASURES, cooccurrence, grouping_stats, groups_per_test, image_ratings, images_per_group
from ramure.studies.anova import anova_table
from ramure.studies.data import StudyData, load_study_data
from ramure.studies.inference import rating_inference
from ramure.studies.quality import quality_summary, representatives
from ramure.studies.likert import LEVELS
from ramure.metrics.heatmap import collision_summary, draw_collision_matrix
from ramure.metrics.qualifiers import QualifierRegions
from ramure.studies.qualifiers import SynonymTable, labelled_points, qualifier_frequencies
from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ramure.studies.storage import Study

RATED = ("usefulness", "difference")


def analyze(
    data: StudyData, alpha: float = 0.05, synonyms: Sequence[str | os.PathLike] = (), min_usefulness: str | int = "good"
) -> dict:
    """Every statistic of the report as plain JSON-ready data."""
    table = SynonymTable.load(*synonyms)
    ratings, anova = {}, {}
    for measure in RATED:
        means, counts = image_ratings(data, measure, with_counts=True)
        ratings[measure] = dict(mean=_listify(means), count=counts.tolist())
        anova[measure] = anova_table(means.T, alpha)
    result = dict(
        study=data.name,
        grammars=list(data.grammars),
        participants=int(len(set(data.test_participant.tolist()))),
        tests=int(data.n_tests),
        groups=int(len(data.group_test)),
        alpha=alpha,
        grouping=grouping_stats(data),
        cooccurrence={g: cooccurrence(data, g).tolist() for g in data.grammars} | {"all": cooccurrence(data).tolist()},
        ratings=ratings,
        anova=anova,
        qualifiers=dict(
            all=qualifier_frequencies(data, table),
            kept=qualifier_frequencies(data, table, min_usefulness),
            min_usefulness=min_usefulness,
        ),
        collision=collision_matrices(data, table, min_usefulness),
        anova_label=ANOVA_LABEL,
        inference=rating_inference(data, alpha),
        agreement=agreement(data, table),
        representatives=representatives(data),
        quality=quality_summary(data),
        answers=likert_counts(data),
    )
    return _jsonable(result)


#: What the thesis-style ANOVA is, wherever it is shown (report, JSON, CSV).
ANOVA_LABEL = (
    "Reproduction of the thesis's ANOVA tables (\u00a77.3), which treat the 27 per-image mean ratings as independent "
    "values: its degrees of freedom do not depend on the number of participants. Not an inference; see the "
    "participant-level tests."
)


def agreement(data: StudyData, table: SynonymTable) -> dict:
    """Grouping agreement (ARI) per grammar, co-occurrence orders and qualifier agreement."""
    orders = {}
    for key in [*data.grammars, "all"]:
        order, linkage = cooccurrence_order(cooccurrence(data, None if key == "all" else key))
        orders[key] = dict(order=(order + 1).tolist(), linkage=linkage.tolist())
    return dict(
        groupings={g: grouping_agreement(data, g) for g in data.grammars},
        order=orders,
        qualifiers=qualifier_agreement(data, table),
    )


def likert_counts(data: StudyData) -> dict:
    """Answers per level (1-4) of each question and grammar: ``{measure: {grammar: [n1..n4]}}``."""
    out = {}
    for measure in MEASURES:
        values = getattr(data, measure)
        out[measure] = {
            g: np.bincount(values[(data.group_grammar == i) & ~np.isnan(values)].astype(int), minlength=5)[1:].tolist()
            for i, g in enumerate(data.grammars)
        }
    return out


def _jsonable(value):
    """``value`` with every non-finite float made None and numpy scalars made plain."""
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def collision_matrices(data: StudyData, table: SynonymTable | None = None, min_usefulness: str | int = "good") -> dict:
    """The qualifiers' collision matrix (thesis Fig. 4.11) from the study's labelled points.

    Every image of a kept group is a point of each qualifier the group was
    given (:func:`~ramure.studies.qualifiers.labelled_points`); one box per
    qualifier in PCA space.  ``all`` pools the grammars (each in its own PCA
    space, as the thesis did), with ``trim`` 0 and 0.07; ``per_grammar`` uses
    the 0.07 trim.  Empty when no kept group named a vocabulary qualifier.
    """
    rows = labelled_points(data, table, min_usefulness)
    out: dict[str, dict] = {"per_grammar": {}}
    if not rows:
        return out

    def points(rs):
        pts: dict[str, list[tuple[float, float, float]]] = {}
        for r in rs:
            pts.setdefault(r["qualifier"], []).append((r["pc1"], r["pc2"], r["pc3"]))
        return pts

    out["all"] = collision_summary(QualifierRegions(trim=0.07).fit(points(rows)))
    out["all_untrimmed"] = collision_summary(QualifierRegions(trim=0.0).fit(points(rows)))
    for g in sorted({r["grammar"] for r in rows}):
        out["per_grammar"][g] = collision_summary(QualifierRegions(trim=0.07).fit(points([r for r in rows if r["grammar"] == g])))
    return out


def _listify(a):
    return [[None if math.isnan(v) else round(float(v), 6) for v in row] for row in a]


def _safe(name):
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name)


def write_report(
    source: StudyData | Study | str | os.PathLike,
    out_dir: str | os.PathLike,
    alpha: float = 0.05,
    synonyms: Sequence[str | os.PathLike] = (),
    min_usefulness: str | int = "good",
    figures: bool = True,
) -> dict:
    """Write the HTML report and CSVs of ``source`` (StudyData, Study or path).

    Returns the :func:`analyze` result plus ``files`` (the paths written).
    """
    data = source if isinstance(source, StudyData) else load_study_data(source)
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    result = analyze(data, alpha, synonyms, min_usefulness)
    files = []
    files += _write_csvs(data, result, out)
    if figures:
        files += _write_figures(data, result, out)
    write_text(out / "summary.json", json.dumps(result, indent=1, allow_nan=False))
    files.append(out / "summary.json")
    write_text(out / "index.html", _html(result, [f.name for f in files], figures))
    files.append(out / "index.html")
    result["files"] = [os.fspath(f) for f in files]
    return result


# -- CSV -------------------------------------------------------------------------
def _write_rows(path, header, rows):
    with open_atomic(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(rows)
    return path


def _write_csvs(data, result, out):
    files = []
    ids = list(range(1, 28))
    for key, matrix in result["cooccurrence"].items():
        name = "cooccurrence_all.csv" if key == "all" else f"cooccurrence_{_safe(key)}.csv"
        files.append(_write_rows(out / name, ["image", *ids], [[i, *row] for i, row in zip(ids, matrix)]))
    for measure in RATED:
        means = np.array(result["ratings"][measure]["mean"], dtype=float).T  # 27 x grammars
        path = out / f"image_ratings_{measure}.tsv"
        with open_atomic(path, "w", encoding="utf-8") as fh:
            fh.write("\t".join(["image", *data.grammars]) + "\n")
            for i, row in zip(ids, means):
                fh.write("\t".join([str(i), *("" if math.isnan(v) else f"{v:.6g}" for v in row)]) + "\n")
        files.append(path)
    rows = []
    for grammar, stats in result["grouping"].items():
        for what, s in stats.items():
            rows.append([grammar, what, *(s[k] for k in ("n", "mean", "median", "q1", "q3", "min", "max"))])
    files.append(
        _write_rows(out / "grouping_stats.csv", ["grammar", "measure", "n", "mean", "median", "q1", "q3", "min", "max"], rows)
    )
    keys = ("F", "F_crit", "p", "df_between", "df_within", "significant", "verdict")
    rows = [[m, d, *(r.get(k) for k in keys), r.get("error", "")] for m, res in result["anova"].items() for d, r in res.items()]
    rows = [[*r, "thesis reproduction: image means as independent values, not an inference"] for r in rows]
    files.append(_write_rows(out / "anova.csv", ["measure", "test", *keys, "error", "note"], rows))
    files += _write_inference_csvs(data, result, out)
    q = result["qualifiers"]
    rows = []
    for scope in ("kept", "all"):
        for r in q[scope]["qualifiers"]:
            rows.append([scope, r["name"], r["fr"], r["groups"], r["images"], r["tests"], ";".join(r["grammars"])])
    files.append(
        _write_rows(out / "qualifiers.csv", ["groups_kept", "qualifier", "fr", "groups", "images", "tests", "grammars"], rows)
    )
    files.append(
        _write_rows(
            out / "qualifiers_unmatched.csv", ["text", "groups"], [[r["text"], r["groups"]] for r in q["all"]["unmatched"]]
        )
    )
    return files


def _write_inference_csvs(data, result, out):
    """inference.csv, pairwise.csv, agreement.csv and test_quality.csv (see the codebook)."""
    inf = result["inference"]
    rows = []
    for m in MEASURES:
        r = inf[m]
        a, f = r["rm_anova"], r["friedman"]
        rows.append([m, "rm_anova", r["n"], a.get("F"), a.get("df1"), a.get("df2"), a.get("p"), "partial_eta2",
                     a.get("partial_eta2"), *(a.get("partial_eta2_ci") or [None, None]), r["verdict"]])  # fmt: skip
        rows.append([m, "friedman", r["n"], f.get("chi2"), f.get("df"), None, f.get("p"), "kendall_w", f.get("kendall_w"),
                     None, None, ""])  # fmt: skip
        for key in ("mixed_model", "ordinal_model"):
            mm = r.get(key) or {}
            rows.append([m, key, r["n"], mm.get("wald_chi2"), mm.get("wald_df"), None, mm.get("p"), "", None, None, None,
                         mm.get("error", "")])  # fmt: skip
    header = ["measure", "test", "n", "statistic", "df1", "df2", "p", "effect", "effect_value", "ci_low", "ci_high", "note"]
    files = [_write_rows(out / "inference.csv", header, rows)]
    rows = [
        [m, c["a"], c["b"], c["n"], c["mean_difference"], *c["ci"], c["t"], c["df"], c["p"], c["p_holm"], c["d_z"], *c["d_z_ci"]]
        for m in MEASURES
        for c in inf[m]["pairwise"]
    ]
    header = [
        "measure",
        "a",
        "b",
        "n",
        "mean_difference",
        "ci_low",
        "ci_high",
        "t",
        "df",
        "p",
        "p_holm",
        "d_z",
        "d_z_low",
        "d_z_high",
    ]
    files.append(_write_rows(out / "pairwise.csv", header, rows))
    rows = [[g, a["n"], a["pairs"], a["mean"], *a["ci"]] for g, a in result["agreement"]["groupings"].items()]
    files.append(_write_rows(out / "agreement.csv", ["grammar", "participants", "pairs", "mean_ari", "ci_low", "ci_high"], rows))
    from ramure.studies.quality import per_test_quality

    rows = [
        [r["participant"], r["grammar"], r["seconds"], r["groups"], r["rated_share"], ";".join(r["flags"])]
        for r in per_test_quality(data)
    ]
    header = ["participant", "grammar", "seconds", "groups", "rated_share", "flags"]
    files.append(_write_rows(out / "test_quality.csv", header, rows))
    return files


# -- figures ---------------------------------------------------------------------
def _figure(width, height):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _write_figures(data, result, out):
    files = [
        _cooccurrence_figure(result, out / "cooccurrence.png"),
        _grouping_figure(data, out / "grouping.png"),
        _ratings_figure(result, out / "ratings.png"),
    ]
    if result["qualifiers"]["all"]["qualifiers"]:
        files.append(_qualifier_figure(result, out / "qualifiers.png"))
    if result["collision"].get("all"):
        files.append(_collision_figure(result, out / "collision.png"))
    files.append(_dendrogram_figure(result, out / "dendrogram.png"))
    files.append(_answers_figure(result, out / "answers.png"))
    return files


def _dendrogram_figure(result, path):
    """Per grammar (and pooled): the average-linkage dendrogram over the co-occurrence in its order."""
    from matplotlib.collections import LineCollection
    from scipy.cluster.hierarchy import dendrogram

    panels = ["all", *result["grammars"]]
    fig = _figure(3.4 * len(panels), 4.6)
    axes = fig.subplots(2, len(panels), squeeze=False, height_ratios=[1, 2.2])
    for col, key in enumerate(panels):
        tree = result["agreement"]["order"][key]
        d = dendrogram(np.array(tree["linkage"], dtype=float), no_plot=True)
        top, ax = axes[0, col], axes[1, col]
        links = [np.column_stack([xs, ys]) for xs, ys in zip(d["icoord"], d["dcoord"])]
        top.add_collection(LineCollection(links, colors="#345", linewidths=0.8))
        top.set_ylim(0, max(1e-9, max(max(ys) for ys in d["dcoord"])) * 1.05)
        top.set_xlim(0, 10 * 27)
        top.set_xticks([])
        top.set_ylabel("1 − share grouped", fontsize=8)
        top.set_title(f"{'all grammars' if key == 'all' else key}", fontsize=10)
        order = np.array(tree["order"]) - 1
        m = np.array(result["cooccurrence"][key], dtype=float)
        n = max(m.diagonal().max(), 1)
        ax.imshow((m / n)[np.ix_(order, order)], cmap="magma", vmin=0, vmax=1, interpolation="nearest")
        ax.set_xticks([])  # same order as the rows; 27 more labels per panel doubled the figure's time
        ax.set_yticks(range(27), order + 1, fontsize=5)
    write_with(path, fig.savefig)
    return path


_LEVEL_COLOURS = ("#c0392b", "#f1a58f", "#9fd3a8", "#1e8449")


def _answers_figure(result, path):
    """Diverging stacked bars: share of each answer level per question and grammar.

    Poor and fair extend left of zero, good and excellent right, so a bar's balance
    reads at a glance; the count of answers is written at the right.
    """
    rows = [(m, g) for m in MEASURES for g in result["grammars"]]
    fig = _figure(8.0, 1.2 + 0.32 * len(rows))
    ax = fig.subplots()
    for y, (measure, grammar) in enumerate(rows):
        counts = np.array(result["answers"][measure][grammar], dtype=float)
        total = counts.sum()
        share = counts / total if total else counts
        starts = [-share[1] - share[0], -share[1], 0.0, share[2]]
        for level in range(4):
            ax.barh(
                y,
                share[level],
                left=starts[level],
                color=_LEVEL_COLOURS[level],
                height=0.7,
                label=LEVELS[level] if y == 0 else None,
            )
        ax.text(1.02, y, f"n = {int(total)}", va="center", fontsize=7, in_layout=False)
    ax.axvline(0, color="k", lw=0.8)
    ax.set_yticks(range(len(rows)), [f"{m.replace('_', ' ')} · {g}" for m, g in rows], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlim(-1, 1.15)
    ax.set_xticks([-1, -0.5, 0, 0.5, 1], ["100 %", "50 %", "0", "50 %", "100 %"])
    ax.set_xlabel("share of answers (poor, fair ← | → good, excellent)")
    fig.legend(ncols=4, loc="outside lower center", fontsize=8, frameon=False)
    write_with(path, fig.savefig)
    return path


def _collision_figure(result, path):
    """Heat map of the pooled collision matrix (7 % trimmed), thesis Fig. 4.11."""
    c = result["collision"]["all"]
    size = 2.5 + 0.42 * len(c["names"])
    fig = _figure(size + 1.0, size)
    ax = fig.subplots()
    image = draw_collision_matrix(ax, c["matrix"], c["names"], title=f"collision matrix (mean {c['mean']:.1f} %, 7 % trimmed)")
    _cell_texts_out_of_layout(ax)
    fig.colorbar(image, ax=ax, shrink=0.8, label="% of A's points in B's box")
    write_with(path, fig.savefig)
    return path


def _cell_texts_out_of_layout(ax):
    """Leave a heat map's cell labels out of the constrained layout.

    They sit inside their cells, so the layout is the same without them, but measuring
    each of hundreds of texts on every layout pass was half of a figure's time."""
    for text in ax.texts:
        text.set_in_layout(False)


def _cooccurrence_figure(result, path):
    panels = ["all", *result["grammars"]]
    cols = min(4, len(panels))
    rows = math.ceil(len(panels) / cols)
    fig = _figure(3.6 * cols, 3.4 * rows)
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False)).ravel()
    ticks = [0, 8, 17, 26]
    for ax, key in zip(axes, panels):
        m = np.array(result["cooccurrence"][key], dtype=float)
        n = max(m.diagonal().max(), 1)
        im = ax.imshow(m / n, cmap="magma", vmin=0, vmax=1, interpolation="nearest")
        for edge in (8.5, 17.5):  # the PC1 blocks 1-9, 10-18, 19-27
            ax.axhline(edge, color="cyan", lw=0.6, alpha=0.7)
            ax.axvline(edge, color="cyan", lw=0.6, alpha=0.7)
        ax.set_xticks(ticks, [t + 1 for t in ticks])
        ax.set_yticks(ticks, [t + 1 for t in ticks])
        ax.set_title(f"{'all grammars' if key == 'all' else key} ({int(n)} tests)", fontsize=10)
    for ax in axes[len(panels) :]:
        ax.set_visible(False)
    fig.colorbar(im, ax=axes.tolist(), shrink=0.8, label="share of tests grouping the pair")
    write_with(path, fig.savefig)
    return path


def _grouping_figure(data, path):
    labels = [*data.grammars, "all"]
    fig = _figure(max(7.0, 1.1 * len(labels) * 2), 3.6)
    left, right = fig.subplots(1, 2)
    for ax, values, title in (
        (left, [groups_per_test(data, g) for g in [*data.grammars, None]], "groups per test"),
        (right, [images_per_group(data, g) for g in [*data.grammars, None]], "images per group"),
    ):
        _boxplot(ax, values, labels)
        ax.set_title(title)
        ax.tick_params(axis="x", rotation=30)
        ax.grid(axis="y", alpha=0.3)
    write_with(path, fig.savefig)
    return path


def _boxplot(ax, values, labels):
    """Tukey box plots (whiskers at 1.5 IQR, mean as a triangle) drawn from artists.

    ``Axes.boxplot`` reads every rcParam, which makes matplotlib pick (and
    import) an interactive backend; drawing the boxes ourselves avoids that.
    """
    from matplotlib.cbook import boxplot_stats
    from matplotlib.patches import Rectangle

    for x, v in enumerate(values, start=1):
        if not len(v):
            continue
        st = boxplot_stats(np.asarray(v, dtype=float))[0]
        ax.add_patch(Rectangle((x - 0.3, st["q1"]), 0.6, st["q3"] - st["q1"], fill=False, lw=1))
        ax.plot([x - 0.3, x + 0.3], [st["med"]] * 2, color="tab:orange", lw=1.5)
        ax.plot([x, x], [st["whislo"], st["q1"]], [x, x], [st["q3"], st["whishi"]], color="k", lw=1)
        ax.plot([x - 0.15, x + 0.15], [st["whislo"]] * 2, [x - 0.15, x + 0.15], [st["whishi"]] * 2, color="k", lw=1)
        ax.plot([x] * len(st["fliers"]), st["fliers"], "o", mfc="none", mec="k", ms=5)
        ax.plot([x], [st["mean"]], "^", color="tab:green", ms=6)
    ax.set_xticks(range(1, len(values) + 1), labels)
    ax.set_xlim(0.4, len(values) + 0.6)
    ax.autoscale_view(scalex=False)


def _ratings_figure(result, path):
    grammars = result["grammars"]
    fig = _figure(12.0, 0.9 + 0.75 * len(grammars) * 2)
    axes = fig.subplots(2, 1)
    for ax, measure in zip(axes, RATED):
        m = np.array(result["ratings"][measure]["mean"], dtype=float)
        im = ax.imshow(m, cmap="RdYlGn", vmin=1, vmax=4, aspect="auto", interpolation="nearest")
        ax.set_yticks(range(len(grammars)), grammars)
        ax.set_xticks(range(27), range(1, 28), fontsize=7)
        ax.set_title(f"mean {measure} per image (1 = poor ... 4 = excellent)", fontsize=10)
        for (i, j), v in np.ndenumerate(m):
            if not math.isnan(v):
                ax.text(j, i, f"{v:.1f}", ha="center", va="center", fontsize=6, in_layout=False)
        fig.colorbar(im, ax=ax, ticks=[1, 2, 3, 4], shrink=0.9)
    write_with(path, fig.savefig)
    return path


def _qualifier_figure(result, path):
    q = result["qualifiers"]
    names = [r["name"] for r in q["all"]["qualifiers"]][::-1]
    all_ = {r["name"]: r["groups"] for r in q["all"]["qualifiers"]}
    kept = {r["name"]: r["groups"] for r in q["kept"]["qualifiers"]}
    fig = _figure(6.5, 0.9 + 0.3 * len(names))
    ax = fig.subplots()
    y = np.arange(len(names))
    ax.barh(y + 0.2, [all_[n] for n in names], height=0.4, label="all groups", color="#9ab")
    ax.barh(
        y - 0.2, [kept.get(n, 0) for n in names], height=0.4, label=f"groups rated {q['min_usefulness']} or better", color="#2a6"
    )
    ax.set_yticks(y, names)
    ax.set_xlabel("groups named")
    ax.legend(loc="lower right", fontsize=8)
    write_with(path, fig.savefig)
    return path


# -- HTML ------------------------------------------------------------------------
def _ci(pair, digits=2):
    low, high = pair
    return "–" if low is None or high is None else f"[{_fmt(low, digits)}, {_fmt(high, digits)}]"


def _inference_html(result):
    e = html.escape
    inf = result["inference"]
    parts = [
        f"<h2>Inference, participants as the unit (α = {inf['alpha']:g})</h2>",
        "<p class='note'>Each participant's mean rating of their groups per grammar enters the "
        "repeated-measures ANOVA, Friedman's test and the paired contrasts (Holm-corrected). The mixed "
        "model takes every rated group, with random intercepts for the participant and for the test "
        "(the participant's pass over one grammar's pictures); the ordinal model treats the levels as "
        f"ordered categories, with standard errors clustered by participant. Below {inf['min_participants']} participants who "
        "rated every grammar no verdict is drawn: that is the N at which a paired comparison detects a "
        "large effect (d<sub>z</sub> = 0.8) with 80 % power.</p>",
    ]
    rows, pair_rows = [], []
    for measure in MEASURES:
        r = inf[measure]
        for w in r["warnings"]:
            parts.append(f"<p class='warn'>{e(measure.replace('_', ' '))}: {e(w)}</p>")
        a, f = r["rm_anova"], r["friedman"]
        label = e(measure.replace("_", " "))
        rows.append(
            [
                label,
                "RM-ANOVA",
                *(
                    [e(a["error"]), "", "", ""]
                    if "error" in a
                    else [
                        f"F({a['df1']}, {a['df2']}) = {_fmt(a['F'])}",
                        _fmt(a["p"]),
                        f"η²<sub>p</sub> = {_fmt(a['partial_eta2'], 2)}",
                        _ci(a["partial_eta2_ci"]),
                    ]
                ),
            ]
        )
        rows.append(
            [
                label,
                "Friedman",
                *(
                    [e(f["error"]), "", "", ""]
                    if "error" in f
                    else [f"χ²({f['df']}) = {_fmt(f['chi2'])}", _fmt(f["p"]), f"W = {_fmt(f['kendall_w'], 2)}", ""]
                ),
            ]
        )
        for key, name, stat in (("mixed_model", "mixed model", "estimate"), ("ordinal_model", "ordinal model", "odds_ratio")):
            m = r.get(key, {})
            if not m:
                continue
            if "error" in m:
                rows.append([label, name, e(m["error"]), "", "", ""])
                continue
            ci_key = "ci" if stat == "estimate" else "odds_ratio_ci"
            effects = "; ".join(
                f"{e(x['grammar'])} − {e(m['reference'])}: {_fmt(x[stat], 2)} {_ci(x[ci_key])}" for x in m["effects"]
            )
            what = "difference" if stat == "estimate" else "odds ratio"
            rows.append(
                [label, name, f"Wald χ²({m['wald_df']}) = {_fmt(m['wald_chi2'])}", _fmt(m["p"]), f"{what}: {effects}", ""]
            )
        rows.append([label, "<strong>verdict</strong>", e(r["verdict"]), "", "", ""])
        for c in r["pairwise"]:
            pair_rows.append(
                [
                    label,
                    f"{e(c['b'])} − {e(c['a'])}",
                    _fmt(c["mean_difference"], 2),
                    _ci(c["ci"]),
                    _fmt(c["d_z"], 2),
                    _ci(c["d_z_ci"]),
                    _fmt(c["p"]),
                    _fmt(c["p_holm"]),
                    _fmt(c["reject"]),
                ]
            )
    parts.append(_table(["measure", "test", "statistic", "p", "effect size", "95 % CI"], rows))
    if pair_rows:
        parts.append("<h3>Paired contrasts</h3>")
        parts.append(
            _table(["measure", "contrast", "mean diff.", "95 % CI", "d_z", "95 % CI", "p", "p (Holm)", "reject"], pair_rows)
        )
    return parts


def _agreement_html(result, figures):
    e = html.escape
    ag = result["agreement"]
    parts = [
        "<h2>Agreement between participants</h2><p class='note'>Adjusted Rand index of every pair of "
        "participants' groupings of a grammar (0 = chance, 1 = identical), with a bootstrap 95 % CI over "
        "participants. The heat maps order the images by average-linkage clustering of the co-occurrence; "
        "the dendrograms above them show the clustering.</p>"
    ]
    rows = [[e(g), a["n"], a["pairs"], _fmt(a["mean"], 3), _ci(a["ci"], 3)] for g, a in ag["groupings"].items()]
    parts.append(_table(["grammar", "participants", "pairs", "mean ARI", "95 % CI"], rows))
    if figures:
        parts.append("<img src='dendrogram.png' alt='dendrograms and ordered co-occurrence'>")
    q = ag["qualifiers"]
    share = "–" if q["coded_share"] is None else f"{100 * q['coded_share']:.1f} %"
    parts.append(
        "<h3>Qualifier coding</h3><p class='note'>The synonym table coded "
        f"{share} of the {q['texts']} qualifier texts. Fleiss' κ per qualifier: how consistently the "
        "participants who did a grammar gave (or did not give) it to each of the 27 images.</p>"
    )
    rows = [
        [e(g), e(r["qualifier"]), r["tests"], r["images_named"], _fmt(r["kappa"], 3)]
        for g, lst in q["per_grammar"].items()
        for r in lst
    ]
    if rows:
        header = ["grammar", "qualifier", "tests using it", "images named", "κ"]
        parts.append(f"<details><summary>Fleiss' κ per qualifier</summary>{_table(header, rows)}</details>")
    return parts


def _quality_html(result):
    e = html.escape
    q, reps = result["quality"], result["representatives"]
    parts = [
        "<h2>Representatives</h2><p class='note'>How often the chosen representative is the group's medoid "
        "(the image nearest the group's centre in PCA space), against choosing at random, and the "
        "representative rating (1–4) of each kind of choice.</p>"
    ]
    shares = ("medoid_share", "chance", "quality_medoid", "quality_other")
    rows = [[e(g), r["groups"], *(_fmt(r[k], 2) for k in shares)] for g, r in reps.items()]
    parts.append(_table(["grammar", "groups", "medoid share", "chance", "rating (medoid)", "rating (other)"], rows))
    parts.append("<h2>Time on task and data quality</h2>")
    keys = ("n", "median", "q1", "q3", "min", "max")
    rows = [
        [e(g), *(_fmt(None if s[k] is None else s[k] / 60, 2) if k != "n" else s[k] for k in keys)]
        for g, s in q["time_on_task"].items()
    ]
    parts.append(_table(["grammar", "tests", "median (min)", "q1", "q3", "min", "max"], rows))
    counts = ", ".join(f"{e(f.replace('_', ' '))}: {n}" for f, n in q["flag_counts"].items())
    parts.append(
        f"<p class='note'>Flags — {counts}. Too fast: under {q['too_fast_seconds']:g} s or a third of the median. "
        "Single group / all alone: no sorting. Straight-lining: one level for every answer of three groups or more. "
        "Missed attention: an attention check answered with another option than the one it asked for.</p>"
    )
    if q["flagged"]:
        rows = [
            [e(r["participant"]), e(r["grammar"]), _fmt(r["seconds"] / 60, 2), r["groups"], e(", ".join(r["flags"]))]
            for r in q["flagged"]
        ]
        header = ["participant", "grammar", "minutes", "groups", "flags"]
        parts.append(f"<details open><summary>flagged tests</summary>{_table(header, rows)}</details>")
    return parts


def _fmt(v, digits=3):
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:.{digits}g}" if abs(v) < 1e-3 and v != 0 else f"{v:.{digits}f}".rstrip("0").rstrip(".")
    return html.escape(str(v))


def _table(header, rows):
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" for row in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


_CSS = """body{font-family:system-ui,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:.5em 0 1.5em;font-size:.9em}td,th{border:1px solid #ccc;padding:.25em .6em;
text-align:right}th{background:#eee}td:first-child{text-align:left}img{max-width:100%}
.note{color:#555;font-size:.9em}.warn{background:#fff4d6;border-left:4px solid #e0a800;padding:.4em .8em}"""


def _html(result, files, figures):
    e = html.escape
    parts = [
        f"<!doctype html><html><head><meta charset='utf-8'><title>Study {e(result['study'])}</title>"
        f"<style>{_CSS}</style></head><body>",
        f"<h1>User study “{e(result['study'])}”</h1>",
        f"<p>{result['participants']} participants, {result['tests']} finished tests, "
        f"{result['groups']} groups, grammars: {e(', '.join(result['grammars']))}. "
        f"Likert answers coded 1–4 ({', '.join(LEVELS)}).</p>",
    ]
    parts.append(
        "<h2>Co-occurrence</h2><p class='note'>Share of tests that put two images in the same "
        "group (images 1–27, PC1 varying slowest; lines mark the blocks 1–9, 10–18, 19–27).</p>"
    )
    if figures:
        parts.append("<img src='cooccurrence.png' alt='co-occurrence heat maps'>")
    parts.append("<h2>Grouping</h2>")
    if figures:
        parts.append("<img src='grouping.png' alt='box plots of groups per test and images per group'>")
    keys = ("n", "mean", "median", "q1", "q3", "min", "max")
    rows = [
        [e(g), e(w.replace("_", " ")), *(_fmt(s[k]) for k in keys)]
        for g, stats in result["grouping"].items()
        for w, s in stats.items()
    ]
    parts.append(_table(["grammar", "measure", *keys], rows))
    parts.append(
        "<h2>Answers</h2><p class='note'>Every answer to each question, per grammar: "
        "poor and fair to the left of zero, good and excellent to the right.</p>"
    )
    if figures:
        parts.append("<img src='answers.png' alt='diverging bars of the Likert answers per question and grammar'>")
    parts.append(
        "<h2>Per-image ratings</h2><p class='note'>Each group's rating passes to each of its "
        "images; means over the tests of each grammar.</p>"
    )
    if figures:
        parts.append("<img src='ratings.png' alt='per-image mean ratings'>")
    for measure in RATED:
        m = result["ratings"][measure]["mean"]
        rows = [[str(i + 1), *(_fmt(m[g][i], 2) for g in range(len(result["grammars"])))] for i in range(27)]
        parts.append(f"<details><summary>mean {measure} table</summary>{_table(['image', *result['grammars']], rows)}</details>")
    parts += _inference_html(result)
    parts.append(f"<h2>Reproduction of the thesis's ANOVA tables (α = {result['alpha']:g})</h2>")
    parts.append(f"<p class='warn'>{e(result['anova_label'])}</p>")
    rows = []
    for measure, res in result["anova"].items():
        for test, r in res.items():
            label = test.replace("_", " ")
            if "error" in r:
                rows.append([e(measure), e(label), "–", "–", "–", "–", e(r["error"])])
            else:
                rows.append(
                    [
                        e(measure),
                        e(label),
                        _fmt(r["F"]),
                        _fmt(r["F_crit"]),
                        _fmt(r["p"]),
                        f"{r['df_between']}, {r['df_within']}",
                        e(r["verdict"]),
                    ]
                )
    parts.append(_table(["measure", "across", "F", "F crit", "p", "df", "verdict"], rows))
    q = result["qualifiers"]
    parts.append("<h2>Qualifiers</h2>")
    parts.append(
        f"<p>{q['all']['observations']} qualifiers given ({q['all']['unique_texts']} distinct "
        f"after folding case and accents), {_fmt(q['all']['per_group'], 3)} per group. Groups rated "
        f"{e(str(q['min_usefulness']))} or better for usefulness: {q['kept']['groups']}.</p>"
    )
    if figures and q["all"]["qualifiers"]:
        parts.append("<img src='qualifiers.png' alt='qualifier frequencies'>")
    kept = {r["name"]: r for r in q["kept"]["qualifiers"]}
    rows = [
        [
            e(r["name"]),
            e(r["fr"]),
            r["groups"],
            kept.get(r["name"], {}).get("groups", 0),
            kept.get(r["name"], {}).get("images", 0),
            e(", ".join(r["grammars"])),
        ]
        for r in q["all"]["qualifiers"]
    ]
    parts.append(_table(["qualifier", "French", "groups", "groups kept", "images kept", "grammars"], rows))
    c = result["collision"]
    if c.get("all"):
        parts.append(
            "<h3>Collision matrix</h3><p class='note'>Row A, column B: share of A's points "
            "inside B's box in PCA space (the thesis reports a mean of 66 %, 61 % after trimming "
            f"7 %). Here: {c['all_untrimmed']['mean']:.1f} %, {c['all']['mean']:.1f} % trimmed.</p>"
        )
        if figures:
            parts.append("<img src='collision.png' alt='qualifier collision matrix heat map'>")
        rows = [[e(g), len(m["names"]), _fmt(m["mean"], 3)] for g, m in c["per_grammar"].items()]
        parts.append(_table(["grammar", "qualifiers", "mean collision (%)"], rows))
    if q["all"]["unmatched"]:
        rows = [[e(r["text"]), r["groups"]] for r in q["all"]["unmatched"][:30]]
        parts.append(f"<details><summary>texts outside the vocabulary</summary>{_table(['text', 'groups'], rows)}</details>")
    parts += _agreement_html(result, figures)
    parts += _quality_html(result)
    parts.append("<h2>Files</h2><ul>" + "".join(f"<li><a href='{e(f)}'>{e(f)}</a></li>" for f in files) + "</ul></body></html>")
    return "\n".join(parts)
