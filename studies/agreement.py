"""Agreement between participants: their groupings, and the qualifiers they gave.

* :func:`partition_labels` -- each test's grouping of the 27 images as a label vector;
* :func:`pairwise_ari` -- adjusted Rand index (as scikit-learn's) of every pair of
  participants' groupings of one grammar; :func:`grouping_agreement` its mean with
  a bootstrap 95 % CI that resamples participants (the unit), per grammar;
* :func:`cooccurrence_order` -- the images ordered by average-linkage clustering
  (scipy) of the co-occurrence, with the linkage for a dendrogram;
* :func:`qualifier_agreement` -- for each coded qualifier, Fleiss' kappa
  (statsmodels) of the participants' yes/no "this image is <qualifier>" over the
  27 images of a grammar, and the share of texts the synonym table could code.

An ARI of 0 is the agreement of random groupings of the same sizes, 1 identical
groupings.

>>> from ramure.studies.simulate import simulate_study
>>> data = simulate_study(participants=4, grammars=1, seed=0)
>>> a = grouping_agreement(data, data.grammars[0], n_boot=200)
>>> a["pairs"], 0 < a["mean"] < 1, a["ci"][0] <= a["mean"] <= a["ci"][1]
(6, True, True)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ramure.studies.picks import N_PICKS

if TYPE_CHECKING:
    from ramure.studies.data import StudyData
    from ramure.studies.qualifiers import SynonymTable


def _tests(data, grammar):
    return np.flatnonzero(data.test_grammar == data.grammar_index(grammar))


def partition_labels(data: StudyData, grammar: str) -> np.ndarray:
    """(n_tests of ``grammar``, 27) group labels; an image left out of every group is alone."""
    tests = _tests(data, grammar)
    labels = np.tile(-1 - np.arange(N_PICKS), (len(tests), 1))  # unplaced: a label of its own
    row_of = {t: i for i, t in enumerate(tests.tolist())}
    for g in np.flatnonzero(np.isin(data.group_test, tests)):
        labels[row_of[int(data.group_test[g])], data.membership[g]] = g
    return labels


def pairwise_ari(data: StudyData, grammar: str) -> np.ndarray:
    """Symmetric (n, n) adjusted Rand indices of the groupings of ``grammar`` (diagonal 1).

    The same index as scikit-learn's ``adjusted_rand_score`` (a test checks it), for
    every pair at once: with each grouping as its 27 x 27 "same group" matrix, the pairs
    grouped together by both participants are one matrix product.  Calling scikit-learn
    per pair took 10 ms a pair, 6 s for a 20-participant study of three grammars.
    """
    labels = partition_labels(data, grammar)
    if not len(labels):
        return np.eye(0)
    same = (labels[:, :, None] == labels[:, None, :]).reshape(len(labels), -1).astype(float)
    pairs = N_PICKS * (N_PICKS - 1) / 2
    both = (same @ same.T - N_PICKS) / 2  # image pairs grouped together by both
    each = (same.sum(axis=1) - N_PICKS) / 2  # image pairs grouped together by each
    expected = np.outer(each, each) / pairs
    top = (each[:, None] + each[None, :]) / 2
    with np.errstate(invalid="ignore", divide="ignore"):
        ari = np.where(top != expected, (both - expected) / (top - expected), 1.0)
    np.fill_diagonal(ari, 1.0)
    return ari


def grouping_agreement(data: StudyData, grammar: str, n_boot: int = 2000, seed: int = 0) -> dict:
    """Mean pairwise ARI of ``grammar`` with a percentile bootstrap 95 % CI over participants.

    Each bootstrap sample draws participants with replacement and averages the ARI
    of every pair of draws of distinct participants.
    """
    ari = pairwise_ari(data, grammar)
    n = len(ari)
    if n < 2:
        return dict(n=n, pairs=0, mean=None, ci=[None, None], error=f"needs 2 participants, got {n}")
    upper = ari[np.triu_indices(n, 1)]
    rng = np.random.default_rng(seed)
    # A resample is how many times each participant was drawn (c); its ordered pairs of draws
    # of distinct participants sum to c A c - sum(c_i^2 A_ii) over n^2 - sum(c_i^2) pairs.
    counts = rng.multinomial(n, np.full(n, 1.0 / n), size=n_boot).astype(float)
    square = (counts**2).sum(axis=1)
    pairs_drawn = n * n - square
    sums = ((counts @ ari) * counts).sum(axis=1) - square * np.diag(ari)[0]
    means = sums[pairs_drawn > 0] / pairs_drawn[pairs_drawn > 0]
    low, high = np.percentile(means, [2.5, 97.5]) if len(means) else (np.nan, np.nan)
    return dict(
        n=n, pairs=int(len(upper)), mean=float(upper.mean()), ci=[float(low), float(high)], median=float(np.median(upper))
    )


def cooccurrence_order(counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Leaf order (0-based images) and average linkage of a 27 x 27 co-occurrence count matrix.

    The distance between two images is the share of tests that did *not* group them.
    """
    from scipy.cluster.hierarchy import leaves_list, linkage, optimal_leaf_ordering
    from scipy.spatial.distance import squareform

    c = np.asarray(counts, dtype=float)
    n = max(float(np.diag(c).max()), 1.0)
    dist = 1.0 - c / n
    np.fill_diagonal(dist, 0.0)
    condensed = squareform(np.clip((dist + dist.T) / 2, 0, 1), checks=False)
    z = linkage(condensed, "average")
    z = optimal_leaf_ordering(z, condensed)
    return leaves_list(z), z


def qualifier_agreement(data: StudyData, table: SynonymTable, min_tests: int = 2) -> dict:
    """Fleiss' kappa per grammar and coded qualifier, and the coding's coverage.

    For grammar G and qualifier q, each of G's 27 images is a subject and each test
    of G a rater saying yes (the image's group was given q) or no.  Qualifiers used
    in fewer than ``min_tests`` tests of G are left out.  ``coded_share`` is the share
    of qualifier texts the synonym table maps to at least one vocabulary name.
    """
    from statsmodels.stats.inter_rater import fleiss_kappa

    coded = [table.canonical(t) for t in data.qualifier_text]
    out: dict = dict(texts=len(coded), coded_share=float(np.mean([bool(c) for c in coded])) if coded else None, per_grammar={})
    for grammar in data.grammars:
        tests = _tests(data, grammar)
        said: dict[str, np.ndarray] = {}
        for row, names in zip(data.qualifier_group.tolist(), coded):
            t = int(data.group_test[row])
            if t not in set(tests.tolist()):
                continue
            for name in names:
                said.setdefault(name, np.zeros((len(tests), N_PICKS), dtype=bool))
                said[name][np.searchsorted(tests, t)] |= data.membership[row]
        rows: list[dict] = []
        for name, yes in sorted(said.items()):
            users = int(yes.any(axis=1).sum())
            if users < min_tests or len(tests) < 2:
                continue
            counts = np.column_stack([yes.sum(axis=0), len(tests) - yes.sum(axis=0)])
            with np.errstate(invalid="ignore", divide="ignore"):
                kappa = float(fleiss_kappa(counts))
            rows.append(dict(qualifier=name, tests=users, images_named=int((yes.sum(axis=0) > 0).sum()), kappa=kappa))
        out["per_grammar"][grammar] = sorted(rows, key=lambda r: -r["tests"])
    return out
