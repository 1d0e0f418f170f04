"""PCA of the metric deltas to three components (thesis §5.3), scikit-learn's result without its import.

The components are those of ``sklearn.decomposition.PCA(svd_solver="full")``
(the SVD of the centred data, computed with numpy: importing scikit-learn
costs about a second, a third of the first exploration's budget); the test
suite checks they agree.

:class:`DeltaPCA` centres the (N,10) delta matrix, optionally standardises
each metric by its standard deviation (``standardize=True``; off by default
as in the thesis, where metrics with large deltas dominate), and keeps the
three main components.  Rows with NaN (failed variants) are ignored by
:meth:`~DeltaPCA.fit` and stay NaN after :meth:`~DeltaPCA.transform`.

Each component's sign is fixed so that its largest loading is positive, so
the same data always gives the same axes.  Fewer than three informative
directions (e.g. fewer than four variants) give zero components, not an error.

>>> import numpy as np
>>> X = np.random.default_rng(0).normal(size=(50, 10)) * np.arange(10, 0, -1)
>>> pca = DeltaPCA().fit(X)
>>> pca.transform(X).shape, bool(pca.explained_variance_ratio_[0] > pca.explained_variance_ratio_[1])
((50, 3), True)
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Self

import numpy as np
from numpy.typing import ArrayLike

from ramure.errors import ValueRefused

from .estimator import ParamsMixin, check_rows


class DeltaPCA(ParamsMixin):
    """Three-component PCA of metric deltas.

    Fitted attributes: ``components_`` (3, f), ``explained_variance_`` (3,),
    ``explained_variance_ratio_`` (3,), ``mean_`` (f,), ``scale_`` (f,) (ones
    unless standardised), ``n_features_in_``, ``n_samples_`` (and ``feature_names_in_``
    when fitted on a data frame).  A scikit-learn transformer: it passes ``check_estimator``
    and works in ``make_pipeline(StandardScaler(), DeltaPCA())``.
    """

    _fitted_attribute = "components_"
    _transformer = True

    def __init__(self, n_components: int = 3, standardize: bool = False) -> None:
        self.n_components = n_components
        self.standardize = standardize

    def fit(self, X: ArrayLike, y: object = None) -> Self:
        """Fit the components on deltas ``X`` (variants x metrics); ``y`` is ignored (scikit-learn's
        signature).  Rows with NaN or infinity are left out."""
        k = int(self.n_components)
        if k < 1:
            raise ValueRefused(f"n_components must be >= 1, not {self.n_components}")
        X = check_rows(self, X, fitting=True)
        rows = X[np.all(np.isfinite(X), axis=1)]
        if not len(rows):
            raise ValueRefused("no valid variant to analyse (every variant failed)")
        f = X.shape[1]
        self.n_samples_ = len(rows)
        self.mean_ = rows.mean(axis=0)
        scale = rows.std(axis=0) if self.standardize else np.ones(f)
        self.scale_ = np.where(scale > 0, scale, 1.0)
        Z = (rows - self.mean_) / self.scale_
        components = np.zeros((k, f))
        variance = np.zeros(k)
        usable = min(k, len(rows), f)
        total = float(Z.var(axis=0).sum())
        if usable and total > 0:  # what sklearn's PCA(svd_solver="full") computes, without its import
            _, sv, vt = np.linalg.svd(Z, full_matrices=False)
            components[:usable] = vt[:usable]
            variance[:usable] = sv[:usable] ** 2 / len(rows)
        for c in components:  # deterministic sign: largest loading positive
            if c[np.argmax(np.abs(c))] < 0:
                c *= -1
        self.components_ = components
        self.explained_variance_ = variance
        self.explained_variance_ratio_ = variance / total if total > 0 else np.zeros(k)
        return self

    def transform(self, X: ArrayLike) -> np.ndarray:
        """Project deltas (N, f) to (N, 3); NaN rows stay NaN."""
        self._check_fitted()
        X = check_rows(self, X, fitting=False)
        return ((X - self.mean_) / self.scale_) @ self.components_.T

    def fit_transform(self, X: ArrayLike, y: object = None) -> np.ndarray:
        """:meth:`fit` then :meth:`transform` on the same deltas."""
        return self.fit(X).transform(X)

    def get_feature_names_out(self, input_features: object = None) -> np.ndarray:
        """The output columns' names, ``deltapca0``, ``deltapca1``, ... (scikit-learn's spelling)."""
        self._check_fitted()
        return np.asarray([f"deltapca{i}" for i in range(len(self.components_))], dtype=object)

    def to_dict(self, metric_names: Iterable[str] | None = None) -> dict:
        """JSON-able description (what ``pca.json`` holds)."""
        return {
            "metrics": list(metric_names) if metric_names is not None else None,
            "components": self.components_.tolist(),
            "explained_variance": self.explained_variance_.tolist(),
            "explained_variance_ratio": self.explained_variance_ratio_.tolist(),
            "mean": self.mean_.tolist(),
            "scale": self.scale_.tolist(),
            "standardized": bool(self.standardize),
            "n_samples": int(self.n_samples_),
        }
