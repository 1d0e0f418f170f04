"""Variant design, sweep (serial, pool, cache, progress, cancel, failures) and PCA."""

import threading

import numpy as np
import pytest

from ramure.lsys import LSystem, RamureError, ValueRefused
from ramure.metrics import DeltaPCA, SweepCancelled, VariantSweep, variant_design
from ramure.metrics.plant import METRIC_NAMES, plant_metrics

HONDA = "grammars/honda_sympodial.lsys"


def test_grid_design_counts_and_values():
    ls = LSystem.from_file(HONDA)
    d = variant_design(ls.constants, len(ls.grammar.rules))
    assert len(d) == 3**5 * 2 == 486
    assert d.names == ("r1", "r2", "a1", "a2", "wr")
    assert sorted(set(d.values[:, 0].tolist())) == [0.81, 0.9, 0.99]
    assert sorted(set(d.values[:, 4].tolist())) == [0.6363, 0.707, 0.7777]  # Table 3.1
    assert d.rules[:243].tolist() == [0] * 243 and d.rules[243:].tolist() == [1] * 243
    assert np.all(d.levels[121] == 0)  # the all-original combination, once per rule
    assert np.all(d.levels[243 + 121] == 0)
    small = variant_design(ls.constants, 2, names="r1,a2", beta=0.2)
    assert len(small) == 9 * 2 and small.combination(0) == {"rule": 0, "constants": {"r1": 0.72, "a2": 48.0}}
    mono = LSystem.from_file("grammars/honda_monopodial.lsys")
    assert len(variant_design(mono.constants, len(mono.grammar.rules))) == 3**6 * 3 == 2187


def test_sampled_designs():
    consts = {"a": 1.0, "b": 2.0, "c": 3.0}
    for mode in ("lhs", "sobol"):
        d = variant_design(consts, 3, mode=mode, n_samples=20, seed=1)
        assert len(d) == 60 and d.levels.min() >= -1 and d.levels.max() <= 1
        assert np.all((d.values >= np.array([0.9, 1.8, 2.7]) - 1e-12) & (d.values <= np.array([1.1, 2.2, 3.3]) + 1e-12))
    lhs = variant_design(consts, 1, mode="lhs", n_samples=10, seed=0)
    # a Latin hypercube puts exactly one sample in each of the 10 strata of every constant
    strata = np.floor((lhs.levels + 1) / 2 * 10).astype(int)
    assert all(sorted(col) == list(range(10)) for col in strata.T)


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        ({"beta": 0}, ValueRefused, "beta"),
        ({"beta": -0.1}, ValueRefused, "beta"),
        ({"names": ["zz"]}, RamureError, "unknown constant"),
        ({"names": ["z"]}, RamureError, "equal 0"),
        ({"mode": "random"}, RamureError, "mode"),
        ({"mode": "lhs", "n_samples": 0}, ValueRefused, "n_samples"),
    ],
)
def test_design_refuses_bad_input(kwargs, error, match):
    with pytest.raises(error, match=match):
        variant_design({"a": 1.0, "z": 0.0}, 2, **kwargs)


def test_grid_too_large_is_refused_with_a_hint():
    with pytest.raises(ValueRefused, match="lhs"):
        variant_design({f"k{i}": 1.0 for i in range(12)}, 2)


def test_each_variant_changes_only_its_rule():
    ls = LSystem.from_file(HONDA)
    sweep = VariantSweep(n=4, constants=["r1"], n_jobs=1, cache=False).fit(ls)
    assert sweep.n_variants_ == 6
    for i in range(6):
        c = sweep.combination(i)
        expect = ls.derive(n=4, params=c).skeleton()
        assert np.allclose(sweep.metrics_[i], np.array(plant_metrics(expect)))
    # rule 0 (A) draws only the trunk's first internode, so r1 on rule 0 only moves its children
    assert np.allclose(sweep.deltas_[1], 0) and np.allclose(sweep.deltas_[4], 0)
    assert not np.allclose(sweep.deltas_[0], 0)
    assert sweep.deltas_[5, METRIC_NAMES.index("total_length")] > 0  # r1 * 1.1 on rule B: longer


def test_pool_gives_the_same_result_as_serial_and_reports_progress():
    ls = LSystem.from_file(HONDA)
    serial = VariantSweep(n=4, n_jobs=1, cache=False).fit(ls)
    seen = []
    pooled = VariantSweep(n=4, n_jobs=2, chunk_size=40, cache=False).fit(ls, progress=lambda d, t: seen.append((d, t)))
    assert np.array_equal(serial.metrics_, pooled.metrics_)
    # both rules read all five constants: only the all-original combinations (= the base) are skipped
    assert pooled.n_derived_ == 484
    assert seen[0] == (0, 484) and seen[-1] == (484, 484) and [d for d, _ in seen] == sorted(d for d, _ in seen)
    assert len(seen) == 1 + len(range(0, 484, 40))


def test_pool_without_fork():
    # what a GUI uses when it sweeps from a background thread: everything must pickle
    a = VariantSweep(n=3, n_jobs=2, cache=False, mp_context="forkserver").fit(HONDA)
    b = VariantSweep(n=3, n_jobs=1, cache=False).fit(HONDA)
    assert np.array_equal(a.metrics_, b.metrics_)


@pytest.mark.parametrize("jobs", [1, 2])
def test_cancel_stops_the_sweep(jobs, tmp_path):
    ls = LSystem.from_file(HONDA)
    stop = threading.Event()
    calls = []

    def progress(done, total):
        calls.append(done)
        if done:
            stop.set()

    sweep = VariantSweep(n=5, n_jobs=jobs, chunk_size=10, cache_dir=tmp_path)
    with pytest.raises(SweepCancelled):
        sweep.fit(ls, progress=progress, cancel=stop)
    assert calls and calls[-1] < 486
    assert not list(tmp_path.rglob("*.npz"))  # nothing cached


def test_cancel_from_another_thread():
    ls = LSystem.from_file(HONDA)
    sweep = VariantSweep(n=5, n_jobs=2, chunk_size=8, cache=False)
    sweep_progress = []
    timer = threading.Timer(0.2, sweep.cancel)
    timer.start()
    with pytest.raises(SweepCancelled):
        sweep.fit(ls, progress=lambda d, t: sweep_progress.append(d) or __import__("time").sleep(0.02))
    timer.cancel()


def test_identical_variants_are_derived_once():
    mono = LSystem.from_file("grammars/honda_monopodial.lsys")
    # A reads r1 r2 a0 d wr (not a2), B and C read r1 r2 a2 wr: 3^5 + 3^4 + 3^4 distinct plants, minus 3 bases
    design_sweep = VariantSweep(n=3, n_jobs=1, cache=False).fit(mono)
    assert design_sweep.n_variants_ == 2187 and design_sweep.n_derived_ == 243 + 81 + 81 - 3
    # every variant's metrics still equal a direct derivation of it
    for i in [0, 5, 728, 729, 1000, 2186]:
        c = design_sweep.combination(i)
        direct = plant_metrics(mono.derive(n=3, params=c).skeleton())
        assert np.allclose(design_sweep.metrics_[i], np.array(direct))


def test_cache_makes_the_second_run_a_read(tmp_path):
    ls = LSystem.from_file(HONDA)
    first = VariantSweep(n=4, n_jobs=1, cache_dir=tmp_path).fit(ls)
    again = VariantSweep(n=4, n_jobs=1, cache_dir=tmp_path).fit(ls)
    assert not first.from_cache_ and again.from_cache_
    assert np.array_equal(first.metrics_, again.metrics_) and np.array_equal(first.base_metrics_, again.base_metrics_)
    assert again.seconds_ < first.seconds_
    other = VariantSweep(n=4, n_jobs=1, beta=0.2, cache_dir=tmp_path).fit(ls)
    assert not other.from_cache_
    ls.constants["r1"] = 0.85
    assert not VariantSweep(n=4, n_jobs=1, cache_dir=tmp_path).fit(ls).from_cache_
    assert len(list(tmp_path.rglob("*.npz"))) == 3


def test_cache_dir_from_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("RAMURE_CACHE", str(tmp_path))
    VariantSweep(n=2, n_jobs=1, constants="r1").fit(HONDA)
    assert len(list(tmp_path.rglob("*.npz"))) == 1


def test_failed_variants_are_flagged_and_left_out():
    text = "#define k 1\n#define s 0.5\nn: 2\nw: A(1)\np:\n A(x) -> F(x/(k-1.1))[+(30)F(s)]A(x)\n"
    sweep = VariantSweep(n_jobs=1, cache=False).fit(LSystem.from_text(text))
    failed = sweep.design_.values[:, 0] == 1.1
    assert sweep.failed_.tolist() == failed.tolist()
    assert np.isnan(sweep.deltas_[failed]).all() and np.isfinite(sweep.deltas_[~failed]).all()
    pts = DeltaPCA().fit_transform(sweep.deltas_)
    assert np.isnan(pts[failed]).all() and np.isfinite(pts[~failed]).all()


def test_unfitted_and_bad_configuration():
    with pytest.raises(RamureError, match="not fitted"):
        VariantSweep().combination(0)
    with pytest.raises(ValueRefused, match="n_jobs"):
        VariantSweep(n_jobs=0).fit(HONDA)
    with pytest.raises(RamureError, match="no such grammar"):
        VariantSweep().fit("nowhere.lsys")


def test_pca_matches_scikit_learn_and_standardises():
    from sklearn.decomposition import PCA

    rng = np.random.default_rng(0)
    X = rng.normal(size=(200, 10)) @ rng.normal(size=(10, 10))
    ours = DeltaPCA().fit(X)
    ref = PCA(3).fit(X)
    assert ours.explained_variance_ratio_ == pytest.approx(ref.explained_variance_ratio_)
    assert np.abs(ours.transform(X)) == pytest.approx(np.abs(ref.transform(X)))
    assert all(c[np.argmax(np.abs(c))] > 0 for c in ours.components_)
    std = DeltaPCA(standardize=True).fit(X)
    assert std.scale_ == pytest.approx(X.std(axis=0))
    assert std.transform(X).std(axis=0) ** 2 == pytest.approx(std.explained_variance_)


def test_pca_of_degenerate_data():
    X = np.zeros((5, 10))
    X[:, 0] = np.arange(5)
    pca = DeltaPCA().fit(X)
    assert pca.explained_variance_ratio_ == pytest.approx([1, 0, 0])
    assert DeltaPCA().fit(np.zeros((4, 10))).transform(np.zeros((4, 10))) == pytest.approx(np.zeros((4, 3)))
    assert DeltaPCA().fit(np.ones((2, 10))).components_.shape == (3, 10)


def test_hidden_constants_sweep_a_grammar_without_define_and_say_what_they_changed():
    """Issue 35 section 2: literals and probabilities vary when no #define does; each variant
    says what it changed in the grammar's own words."""
    from ramure.lsys import LSystem

    text = "n: 4\nw: !(0.1)A(1)\np:\n .6 A(x) -> F(x)[+(30)A(x*0.5)][-(30)A(x*0.5)]A(x)\n .4 A(x) -> F(x)A(x)\n"
    with pytest.raises(RamureError, match="no non-zero #define"):
        VariantSweep(n_jobs=1, cache=False).fit(LSystem.from_text(text))
    sweep = VariantSweep(n_jobs=1, cache=False, hidden=True).fit(LSystem.from_text(text))
    # rule 0: +(30), -(30), 0.5 twice, p0; rule 1: p1; axiom: 0.1, 1 -> 8 knobs alone, then the
    # two 30s and the two 0.5s of rule 0 together: 10 sets, each at -10 % and +10 %
    assert sweep.n_variants_ == 20 and sweep.changes_.all() and not sweep.failed_.any()
    texts = [sweep.describe(i)["text"] for i in range(sweep.n_variants_)]
    assert "rule 0 (A(x)): +(30) -> +(27)" in texts
    assert "rule 1 (A(x)): probability 0.4 -> probability 0.44" in texts
    assert "the axiom (the plant derived again): !(0.1) -> !(0.11)" in texts
    assert "rule 0 (A(x)): A(x*0.5) -> A(x*0.55) (x2)" in texts
    # the axiom's width reaches the radii; the combination is what a session applies
    i = texts.index("the axiom (the plant derived again): !(0.1) -> !(0.11)")
    assert sweep.combination(i) == {"rule": None, "constants": {"~w0.0": 0.11}}
    assert sweep.deltas_[i, 9] == pytest.approx(10.0)  # mean radius +10 %


def test_a_grammar_without_any_number_says_so_with_hidden_constants():
    from ramure.lsys import LSystem

    with pytest.raises(RamureError, match="no non-zero #define constant, numeric literal or rule probability"):
        VariantSweep(n_jobs=1, cache=False, hidden=True).fit(LSystem.from_text("n: 2\nw: A\np:\n A -> F[+A][-A]A\n"))
