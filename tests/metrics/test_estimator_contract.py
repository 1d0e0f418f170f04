"""scikit-learn's estimator contract: ``check_estimator`` on DeltaPCA, QualifierRegions, QualifierModel.

Every check runs; the only ones left out are QualifierModel's checks that fit on random data of
1 to 5 columns: the model is defined on the fifteen qualifier metrics (10 plant deltas, optionally
5 shape deltas), so a fit on 2 or 3 columns is refused by design.  Each is named below with that
reason, and the test asserts it really fails for that reason (so the list cannot go stale);
``test_qualifier_model_keeps_the_contract_on_its_own_data`` checks the same properties on 10
columns.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest

sklearn = pytest.importorskip("sklearn")
from sklearn.base import clone  # noqa: E402
from sklearn.exceptions import NotFittedError  # noqa: E402
from sklearn.pipeline import make_pipeline  # noqa: E402
from sklearn.preprocessing import StandardScaler  # noqa: E402
from sklearn.utils.estimator_checks import check_estimator  # noqa: E402
from sklearn.utils.validation import check_is_fitted  # noqa: E402

from ramure.errors import ValueRefused  # noqa: E402
from ramure.metrics.pca import DeltaPCA  # noqa: E402
from ramure.metrics.qualifiers import QualifierModel, QualifierRegions  # noqa: E402

ARBITRARY_COLUMNS = "fits on random data of 1-5 columns; QualifierModel takes the 10 or 15 qualifier metrics only"
#: QualifierModel's checks that do not apply, each with its reason.
QUALIFIER_MODEL_SKIPS = dict.fromkeys(
    [
        "check_fit_score_takes_y",
        "check_estimators_overwrite_params",
        "check_dont_overwrite_parameters",
        "check_estimators_fit_returns_self",
        "check_readonly_memmap_input",
        "check_n_features_in_after_fitting",
        "check_positive_only_tag_during_fit",
        "check_estimators_dtypes",
        "check_pipeline_consistency",
        "check_estimators_pickle",
        "check_f_contiguous_array_estimator",
        "check_methods_sample_order_invariance",
        "check_methods_subset_invariance",
        "check_dict_unchanged",
        "check_fit_idempotent",
        "check_fit_check_is_fitted",
        "check_n_features_in",
        "check_fit2d_predict1d",
    ],
    ARBITRARY_COLUMNS,
)
#: Needs SCIPY_ARRAY_API=1 in the environment; none of the three claims array-API support.
ENVIRONMENT_SKIPS = {"check_array_api_input"}


def _run(estimator, expected_failures=None):
    results = check_estimator(estimator, expected_failed_checks=expected_failures or {}, on_fail=None, on_skip=None)
    by_status: dict[str, set[str]] = {}
    for r in results:
        by_status.setdefault(r["status"], set()).add(r["check_name"])
    return results, by_status


@pytest.mark.parametrize("estimator", [DeltaPCA(), DeltaPCA(n_components=2, standardize=True), QualifierRegions(trim=0.1)])
def test_check_estimator_passes(estimator):
    results, by_status = _run(estimator)
    failed = [(r["check_name"], repr(r["exception"])) for r in results if r["status"] == "failed"]
    assert failed == []
    assert by_status.get("skipped", set()) <= ENVIRONMENT_SKIPS
    assert len(by_status["passed"]) >= 39  # the whole list ran, not a handful


def test_check_estimator_passes_qualifier_model_but_the_named_checks():
    results, by_status = _run(QualifierModel(), QUALIFIER_MODEL_SKIPS)
    assert [r["check_name"] for r in results if r["status"] == "failed"] == []
    assert by_status.get("skipped", set()) <= ENVIRONMENT_SKIPS
    assert by_status["xfail"] == set(QUALIFIER_MODEL_SKIPS)  # each named check really fails ...
    for r in results:
        if r["status"] == "xfail":  # ... and for the named reason: the column count
            assert "expected deltas of shape (N, 10) or (N, 15)" in str(r["exception"]) or (
                r["check_name"] == "check_positive_only_tag_during_fit"
            ), r
    assert len(by_status["passed"]) >= 20


def _deltas(n=40, seed=0):
    return np.random.default_rng(seed).normal(size=(n, 10))


def test_qualifier_model_keeps_the_contract_on_its_own_data():
    X = _deltas()
    model = QualifierModel(k_nearest=5)
    with pytest.raises(NotFittedError):
        check_is_fitted(model)
    with pytest.raises(NotFittedError, match="not fitted yet"):
        model.scores("dense")
    assert model.fit(X) is model  # fit returns self
    check_is_fitted(model)
    assert model.n_features_in_ == 10 and model.get_params(deep=True) == clone(model).get_params()
    again = QualifierModel(k_nearest=5).fit(X.copy(order="F"))
    np.testing.assert_array_equal(again.scores_, model.scores_)  # idempotent, order-free memory layout
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(model)).scores_, model.scores_)
    reordered = QualifierModel().fit(X[::-1])
    np.testing.assert_allclose(reordered.scores_[::-1], model.scores_)  # row-wise scores
    np.testing.assert_array_equal(X, _deltas())  # the input is not written to


def test_not_fitted_is_sklearns_error_and_a_ramure_refusal():
    for estimator, call in [
        (DeltaPCA(), lambda e: e.transform(np.zeros((2, 3)))),
        (QualifierRegions(), lambda e: e.contains("dense", np.zeros((1, 3)))),
        (QualifierModel(), lambda e: e.picks()),
    ]:
        with pytest.raises(NotFittedError) as info:
            call(estimator)
        assert isinstance(info.value, ValueRefused) and isinstance(info.value, AttributeError), info.value
        assert not estimator.__sklearn_is_fitted__()


def test_delta_pca_in_a_pipeline_matches_standardised_pca():
    X = np.random.default_rng(3).normal(size=(60, 10)) * np.arange(1, 11)
    pipe = make_pipeline(StandardScaler(), DeltaPCA())
    out = pipe.fit_transform(X)
    direct = DeltaPCA(standardize=True).fit(X)
    assert out.shape == (60, 3)
    np.testing.assert_allclose(out, direct.transform(X), atol=1e-9)  # StandardScaler == standardize=True
    assert list(pipe.get_feature_names_out()) == ["deltapca0", "deltapca1", "deltapca2"]
    assert "deltapca__n_components" in pipe.get_params(deep=True)
    pipe.set_params(deltapca__n_components=2)
    assert pipe.fit(X).transform(X).shape == (60, 2)


def test_delta_pca_keeps_the_nan_rows_of_failed_variants():
    X = _deltas(30)
    X[4] = np.nan
    pca = DeltaPCA().fit(X)
    assert pca.n_samples_ == 29 and pca.n_features_in_ == 10
    out = pca.transform(X)
    assert np.isnan(out[4]).all() and np.isfinite(np.delete(out, 4, axis=0)).all()


def test_delta_pca_refuses_wrong_width_in_sklearns_words():
    pca = DeltaPCA().fit(_deltas())
    with pytest.raises(ValueRefused, match="X has 4 features, but DeltaPCA is expecting 10 features as input"):
        pca.transform(np.zeros((2, 4)))


def test_qualifier_regions_fit_on_labels_equals_fit_on_a_mapping():
    rng = np.random.default_rng(1)
    points = {"dense": rng.normal(size=(12, 3)), "petit": rng.normal(1.0, size=(9, 3))}
    X = np.vstack(list(points.values()))
    y = ["dense"] * 12 + ["petit"] * 9
    by_mapping, by_labels = QualifierRegions().fit(points), QualifierRegions().fit(X, y)
    assert by_labels.names_ == by_mapping.names_ == ["dense", "small"]
    np.testing.assert_array_equal(by_labels.collision_matrix_, by_mapping.collision_matrix_)
    assert by_labels.n_features_in_ == by_mapping.n_features_in_ == 3
    with pytest.raises(ValueRefused, match="requires y to be passed"):
        QualifierRegions().fit(X)
    with pytest.raises(ValueRefused, match="one qualifier name per point"):
        QualifierRegions().fit(X, y[:-1])
