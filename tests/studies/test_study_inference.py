"""Statistics with participants as the unit, checked against models fitted independently.

The 20-participant study is simulated once, exported to CSV as a researcher would, and
its report's numbers are compared with statsmodels' and scipy's own fits on that CSV
(formula interface, stock ``OrderedModel``, ``AnovaRM``): a different path to the same
models, so a wrong aggregation, a wrong design or a wrong column would show.
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pandas as pd
import pytest
from scipy.stats import friedmanchisquare, ttest_rel
from sklearn.metrics import adjusted_rand_score

from ramure.studies.agreement import cooccurrence_order, grouping_agreement, pairwise_ari, partition_labels
from ramure.studies.analysis import cooccurrence
from ramure.studies.data import load_study_data
from ramure.studies.export import CODEBOOK, export_csv
from ramure.studies.inference import MIN_PARTICIPANTS, rating_inference
from ramure.studies.picks import lattice_picks
from ramure.studies.quality import per_test_quality, representatives
from ramure.studies.qualifiers import SynonymTable
from ramure.studies.report import write_report
from ramure.studies.simulate import SimulatedParticipant, simulate_study


@pytest.fixture(scope="module")
def study20(tmp_path_factory):
    root = tmp_path_factory.mktemp("study20")
    simulate_study(root / "s.db", participants=20, grammars=3, seed=0)
    export_csv(root / "s.db", root / "csv")
    result = write_report(load_study_data(root / "s.db"), root / "report")
    return root, result


def _groups(root):
    return pd.read_csv(root / "csv" / "groups.csv", dtype={"participant": str})


def test_rm_anova_friedman_and_contrasts_match_fits_on_the_exported_csv(study20):
    from statsmodels.stats.anova import AnovaRM
    from statsmodels.stats.multitest import multipletests

    root, result = study20
    g = _groups(root)
    for measure in ("usefulness", "difference", "representative_quality"):
        means = g.dropna(subset=[measure]).groupby(["participant", "grammar"], as_index=False)[measure].mean()
        table = AnovaRM(means, measure, "participant", within=["grammar"]).fit().anova_table.iloc[0]
        mine = result["inference"][measure]
        a = mine["rm_anova"]
        assert (a["df1"], a["df2"], mine["n"]) == (2, 38, 20)
        assert a["F"] == pytest.approx(table["F Value"], rel=1e-9)
        assert a["p"] == pytest.approx(table["Pr > F"], rel=1e-6)
        assert a["partial_eta2"] == pytest.approx(a["F"] * 2 / (a["F"] * 2 + 38))
        assert a["partial_eta2_ci"][0] <= a["partial_eta2"] <= a["partial_eta2_ci"][1]
        wide = means.pivot(index="participant", columns="grammar", values=measure)
        assert mine["friedman"]["p"] == pytest.approx(friedmanchisquare(*wide.to_numpy().T).pvalue)
        pairs = mine["pairwise"]
        raw = [ttest_rel(wide[c["b"]], wide[c["a"]]).pvalue for c in pairs]
        assert [c["p"] for c in pairs] == pytest.approx(raw)
        assert [c["p_holm"] for c in pairs] == pytest.approx(list(multipletests(raw, method="holm")[1]))
        for c in pairs:
            assert c["ci"][0] < c["mean_difference"] < c["ci"][1]
            assert c["d_z_ci"][0] < c["d_z"] < c["d_z_ci"][1]


def test_mixed_and_ordinal_models_match_fits_on_the_exported_csv(study20):
    import statsmodels.formula.api as smf
    from statsmodels.miscmodels.ordinal_model import OrderedModel
    from statsmodels.regression.mixed_linear_model import MixedLMParams

    root, result = study20
    g = _groups(root)
    for measure in ("usefulness", "difference"):
        d = g.dropna(subset=[measure]).assign(test=lambda f: f["test"].astype(str))
        model = smf.mixedlm(
            f"{measure} ~ C(grammar)", d, groups="participant", re_formula="1", vc_formula={"test": "0 + C(test)"}
        )
        stock = model.fit(reml=True, method=["lbfgs", "powell"])
        mine = result["inference"][measure]["mixed_model"]
        assert mine["n_answers"] == len(d) and mine["n_participants"] == 20
        assert mine["reml_log_likelihood"] >= stock.llf - 1e-6  # never below statsmodels' own start
        # an optimum: started where Ramure ended, the stock fit stays there
        v = mine["variance"]
        start = MixedLMParams.from_components(
            fe_params=np.r_[mine["intercept"], [e["estimate"] for e in mine["effects"]]],
            cov_re=np.array([[v["participant"] / v["residual"]]]),
            vcomp=np.array([v["test"] / v["residual"]]),
        )
        fit = model.fit(reml=True, method=["lbfgs", "powell"], start_params=start)
        assert fit.llf == pytest.approx(mine["reml_log_likelihood"], abs=1e-6)
        for effect in mine["effects"]:
            term = f"C(grammar)[T.{effect['grammar']}]"
            assert effect["estimate"] == pytest.approx(fit.fe_params[term], abs=1e-4)
            assert effect["ci"] == pytest.approx(list(fit.conf_int().loc[term]), abs=1e-3)
        assert mine["variance"]["residual"] == pytest.approx(fit.scale, rel=1e-3)

        X = pd.get_dummies(d[["grammar"]], drop_first=True, dtype=float)
        clusters = {"groups": pd.factorize(d["participant"])[0]}
        ordinal = OrderedModel(d[measure].astype(int), X, distr="logit").fit(
            method="bfgs", disp=False, maxiter=500, cov_type="cluster", cov_kwds=clusters
        )
        mine = result["inference"][measure]["ordinal_model"]
        for effect in mine["effects"]:
            term = f"grammar_{effect['grammar']}"
            assert effect["log_odds"] == pytest.approx(ordinal.params[term], abs=1e-4)
            assert effect["odds_ratio_ci"] == pytest.approx(np.exp(ordinal.conf_int().loc[term]).tolist(), rel=1e-3)
            assert effect["p"] == pytest.approx(ordinal.pvalues[term], rel=1e-2, abs=1e-12)


def test_one_participant_is_never_significant():
    data = simulate_study(participants=1, grammars=3, seed=0)
    result = rating_inference(data)
    for measure in ("usefulness", "difference", "representative_quality"):
        r = result[measure]
        assert r["significant"] is False and "error" in r["rm_anova"]
        assert r["verdict"].startswith("not tested") and "cannot run" in r["warnings"][0]
        assert "error" in r["mixed_model"] and "error" in r["ordinal_model"]


def test_few_participants_get_a_warning_and_no_verdict():
    grammars = {name: lattice_picks(seed=1) for name in ("a", "b", "c")}
    data = simulate_study(participants=5, grammars=grammars, seed=1, effects={"c": 2.5})
    r = rating_inference(data, models=False)["usefulness"]
    assert r["n"] == 5 < MIN_PARTICIPANTS
    assert r["rm_anova"]["p"] < 0.05  # the effect is there ...
    assert r["significant"] is False and "no verdict" in r["verdict"]  # ... but 5 people decide nothing
    assert any("minimum 15" in w for w in r["warnings"])


def test_reports_of_an_empty_study_and_of_an_incomplete_design(tmp_path):
    from ramure.studies.storage import Study

    with Study.create(tmp_path / "e.db", grammars={"a": lattice_picks(), "b": lattice_picks(seed=2)}) as study:
        study.add_participant(consent=True)
    empty = write_report(tmp_path / "e.db", tmp_path / "empty")
    assert empty["tests"] == 0 and empty["inference"]["usefulness"]["significant"] is False
    assert empty["agreement"]["groupings"]["a"]["pairs"] == 0
    # Each participant rates 2 of 3 grammars: no repeated-measures ANOVA, the mixed model decides.
    grammars = {name: lattice_picks(seed=1) for name in ("a", "b", "c")}
    data = simulate_study(participants=24, grammars=grammars, tests_per_participant=2, seed=2, effects={"c": 1.5})
    r = rating_inference(data)["usefulness"]
    assert "error" in r["rm_anova"] and r["mixed_model"]["n_participants"] == 24
    assert r["verdict"].startswith("mixed model") and r["significant"]
    assert write_report(data, tmp_path / "incomplete")["files"]


def test_simulated_grammar_effect_is_recovered():
    # Three identical stimulus sets: only the simulated shift of grammar c separates them.
    grammars = {name: lattice_picks(seed=1) for name in ("a", "b", "c")}
    data = simulate_study(participants=20, grammars=grammars, seed=3, effects={"c": 0.8})
    r = rating_inference(data)["usefulness"]
    assert r["significant"]
    contrasts = {(c["a"], c["b"]): c for c in r["pairwise"]}
    assert contrasts["a", "c"]["reject"] and contrasts["b", "c"]["reject"] and not contrasts["a", "b"]["reject"]
    effects = {e["grammar"]: e for e in r["mixed_model"]["effects"]}
    # Rounding to 1-4 and the ceiling at 4 shrink the shift: recovered between half and all of it.
    assert 0.4 < effects["c"]["estimate"] < 0.8 + 0.1 and effects["c"]["ci"][0] > 0
    assert effects["b"]["ci"][0] < 0 < effects["b"]["ci"][1]
    assert r["mixed_model"]["variance"]["participant"] > 0.05  # the simulated leniency shows up


def test_simulated_qualifiers_code_back_to_their_intended_names():
    person = SimulatedParticipant(seed=5)
    rng = np.random.default_rng(0)
    for _ in range(400):
        person.qualifiers(rng.uniform(-1, 1, 3), int(rng.integers(1, 5)))
    table = SynonymTable.load()
    intended = [(text, name) for text, name in person.said if name is not None]
    assert {name for _, name in intended} >= {"small", "large", "sparse", "dense", "thin", "thick", "symmetric"}
    wrong = [(text, name, table.canonical(text)) for text, name in intended if table.canonical(text) != [name]]
    assert wrong == []


def test_groupings_and_representatives_are_recovered():
    grammars = {"g": lattice_picks(seed=0, noise=0.0, extent=(10.0, 1.0, 1.0))}
    sharp = simulate_study(participants=12, grammars=grammars, noise=0.05, seed=2)
    blurred = simulate_study(participants=12, grammars=grammars, noise=1.0, seed=2)
    from scipy.cluster.hierarchy import fcluster

    _, tree = cooccurrence_order(cooccurrence(sharp))
    blocks = np.repeat([0, 1, 2], 9)
    assert adjusted_rand_score(blocks, fcluster(tree, 3, "maxclust")) == 1.0
    assert grouping_agreement(sharp, "g")["ci"][0] > grouping_agreement(blurred, "g")["ci"][1]
    reps = representatives(sharp)["g"]
    # 80 % choose the medoid, the rest at random: 0.8 + 0.2 * chance expected.
    assert reps["medoid_share"] == pytest.approx(0.8 + 0.2 * reps["chance"], abs=0.12)
    assert reps["quality_medoid"] > reps["quality_other"] + 0.5


def _answer(session, groups, level=3):
    """Set ``groups`` and answer every question at ``level``, then finish."""
    groups = [[int(i) for i in g] for g in groups]
    session.set_groups(groups)
    for label, images in enumerate(groups, start=1):
        if len(images) > 1:
            session.set_representative(label, images[0])
            session.rate(label, representative=level)
        session.rate(label, usefulness=level, difference=level)
        session.add_qualifier(label, "petit")
    session.finish()


def test_pairwise_ari_equals_scikit_learn(tmp_path):
    from ramure.studies.storage import Study

    rng = np.random.default_rng(4)
    with Study.create(tmp_path / "s.db", grammars={"g": lattice_picks()}) as study:
        partitions = [[range(1, 28)], [[i] for i in range(1, 28)]]  # one group; all alone
        partitions += [[np.flatnonzero(lab == k) + 1 for k in np.unique(lab)] for lab in rng.integers(0, 5, (6, 27))]
        for groups in partitions:
            _answer(study.session(study.add_participant(consent=True), "g"), groups, int(rng.integers(1, 5)))
        data = load_study_data(study)
    labels = partition_labels(data, "g")
    expected = np.array([[adjusted_rand_score(a, b) for b in labels] for a in labels])
    assert np.allclose(pairwise_ari(data, "g"), expected, atol=1e-12)


def test_time_on_task_and_flags(study, clock):
    fast = study.add_participant(consent=True)
    s = study.session(fast, "honda")
    clock.advance(20)
    _answer(s, [range(1, 28)], level=2)
    careful = study.add_participant(consent=True)
    s = study.session(careful, "honda")
    clock.advance(900)
    _answer(s, [range(1, 10), range(10, 19), range(19, 28)], level=3)
    varied = study.add_participant(consent=True)
    s = study.session(varied, "honda")
    clock.advance(800)
    _answer(s, [range(1, 10), range(10, 28)], level=4)
    s = study.session(varied, "tree2")
    clock.advance(100)  # over a minute, but under a third of the median (450 s)
    _answer(s, [range(1, 14), range(14, 28)], level=4)
    rows = per_test_quality(load_study_data(study))
    assert [r["seconds"] for r in rows] == pytest.approx([20, 900, 800, 100])
    assert [r["flags"] for r in rows] == [["too_fast", "single_group"], ["straight_lining"], [], ["too_fast"]]


def test_a_missed_attention_check_flags_every_test_of_that_participant(study, clock):
    """Issue 38 §3: attention checks were stored and never looked at again."""
    from ramure.studies.quality import quality_summary

    codes = [study.add_participant(consent=True) for _ in range(3)]
    answers = [{"attention_1": "fair"}, {"attention_1": "good"}, None]  # passed, missed, never reached
    for code, page in zip(codes, answers):
        if page is not None:
            study.record_answers(code, "attention", page)
        for grammar in ("honda", "tree2"):
            clock.advance(600)
            _answer(study.session(code, grammar), [range(1, 10), range(10, 19), range(19, 28)], level=2 + len(grammar) % 2)
    data = load_study_data(study)
    assert data.attention_missed.tolist() == [0, 1, 0]
    rows = per_test_quality(data)
    assert [("missed_attention" in r["flags"]) for r in rows] == [False, False, True, True, False, False]
    summary = quality_summary(data)
    assert summary["flag_counts"]["missed_attention"] == 2
    assert {r["participant"] for r in summary["flagged"] if "missed_attention" in r["flags"]} == {codes[1]}


def test_codebook_describes_every_exported_column(tmp_path):
    simulate_study(tmp_path / "s.db", participants=2, grammars=1)
    files = export_csv(tmp_path / "s.db", tmp_path / "csv")
    described = {(f, c) for f, c, *_ in CODEBOOK}
    exported = set()
    for path in files:
        if path.suffix == ".csv" and path.name != "codebook.csv":
            with open(path, newline="", encoding="utf-8") as fh:
                exported |= {(path.name, column) for column in next(csv.reader(fh))}
    assert exported == described
    with open(tmp_path / "csv" / "codebook.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert {r["levels"] for r in rows if r["column"] == "usefulness"} == {
        "1 = poor, 2 = fair, 3 = good, 4 = excellent; empty = not answered"
    }


def test_report_shows_the_new_sections_and_figures(study20):
    from matplotlib.image import imread

    root, result = study20
    report = root / "report"
    html = (report / "index.html").read_text(encoding="utf-8")
    for part in (
        "Inference, participants as the unit",
        "F(2, 38)",
        "Paired contrasts",
        "Reproduction of the thesis",
        "Not an inference",
        "Agreement between participants",
        "dendrogram.png",
        "answers.png",
        "Representatives",
        "Time on task and data quality",
    ):
        assert part in html, part
    for name in ("dendrogram.png", "answers.png"):
        pixels = imread(report / name)[..., :3]
        assert pixels.std() > 0.05 and (pixels < 0.5).mean() > 0.01, name  # drawn, not blank
    summary = json.loads((report / "summary.json").read_text())
    assert "not an inference" in summary["anova_label"].lower()
    assert summary["inference"]["usefulness"]["rm_anova"]["df2"] == 38
    assert set(summary["agreement"]["groupings"]) == set(summary["grammars"])
    with open(report / "anova.csv", newline="", encoding="utf-8") as fh:
        assert all("not an inference" in row["note"] for row in csv.DictReader(fh))


def test_mixed_model_keeps_the_better_of_two_starts(monkeypatch):
    """Simulated study seed 0: statsmodels' start stops at a lower REML optimum for usefulness
    (-418.2656 against -418.2442 from the moment start); the model reports the better one."""
    import statsmodels.regression.mixed_linear_model as mlm

    from ramure.studies.inference import answers_frame, mixed_model

    data = simulate_study(participants=20, grammars=3, seed=0)
    frame = answers_frame(data, "usefulness")
    likelihoods = []
    fit = mlm.MixedLM.fit

    def spy(self, *args, **kwargs):
        result = fit(self, *args, **kwargs)
        likelihoods.append(result.llf)
        return result

    monkeypatch.setattr(mlm.MixedLM, "fit", spy)
    mine = mixed_model(frame, list(data.grammars))
    stock, moments = likelihoods
    assert moments > stock + 0.01  # the two starts end apart
    assert mine["reml_log_likelihood"] == pytest.approx(moments)
