"""The scikit-learn estimator contract, without importing scikit-learn.

Ramure's estimator-like classes (:class:`~ramure.metrics.pca.DeltaPCA`,
:class:`~ramure.metrics.sweep.VariantSweep`,
:class:`~ramure.metrics.qualifiers.QualifierRegions`,
:class:`~ramure.metrics.qualifiers.QualifierModel`) follow scikit-learn's
conventions so ``sklearn.base.clone`` and grid searches work on them: the
constructor stores its keyword arguments as attributes of the same name
and does nothing else; :meth:`ParamsMixin.get_params` /
:meth:`ParamsMixin.set_params` read and write them; fitted state ends with
``_``; bad parameters raise :class:`ramure.errors.ValueRefused` (a
``ValueError``) when :meth:`fit` checks them.

They also keep scikit-learn's estimator contract, so ``check_estimator`` and
``make_pipeline(StandardScaler(), DeltaPCA())`` work on them: ``fit(X, y=None)``;
:meth:`ParamsMixin.__sklearn_tags__` (NaN rows allowed: a failed variant is a NaN
row); :func:`check_rows` refuses sparse, complex, empty and misshaped input in
scikit-learn's words and records ``n_features_in_`` / ``feature_names_in_``; a
method called before ``fit`` raises :class:`sklearn.exceptions.NotFittedError`
(also a :class:`~ramure.errors.ValueRefused`).  scikit-learn itself (about a
second and a half to import) is imported only by the tags and by that error.

>>> from sklearn.base import clone
>>> from ramure.metrics import DeltaPCA
>>> clone(DeltaPCA(standardize=True)).get_params()
{'n_components': 3, 'standardize': True}
>>> check_n_jobs(None), check_n_jobs(2)
(1, 2)
"""

from __future__ import annotations

import functools
import inspect
import os
import warnings
from typing import Any, Self

import numpy as np

from ramure.errors import ValueRefused


class ParamsMixin:
    """``get_params`` / ``set_params`` / ``repr`` from the constructor's signature, and the tags."""

    #: The fitted attribute whose presence means "fitted" (``check_is_fitted``).
    _fitted_attribute = "n_features_in_"
    #: A transformer (``transform``, ``fit_transform``)?  Read by :meth:`__sklearn_tags__`.
    _transformer = False
    #: Does :meth:`fit` need ``y``?  Read by :meth:`__sklearn_tags__`.
    _y_required = False

    def __sklearn_tags__(self) -> Any:
        """scikit-learn's tags: a dense 2-D float input where NaN rows are allowed (failed variants)."""
        from sklearn.utils import InputTags, Tags, TargetTags, TransformerTags

        return Tags(
            estimator_type=None,
            target_tags=TargetTags(required=self._y_required),
            transformer_tags=TransformerTags() if self._transformer else None,
            input_tags=InputTags(allow_nan=True),
        )

    def __sklearn_is_fitted__(self) -> bool:
        """True once :meth:`fit` has run (what ``sklearn.utils.validation.check_is_fitted`` asks)."""
        return hasattr(self, self._fitted_attribute)

    def _check_fitted(self) -> None:
        if not self.__sklearn_is_fitted__():
            name = type(self).__name__
            raise not_fitted_error()(f"this {name} is not fitted yet: call fit first")

    @classmethod
    def _param_names(cls) -> list:
        sig = inspect.signature(cls.__init__)
        return sorted(
            p.name for p in sig.parameters.values() if p.name != "self" and p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)
        )

    def get_params(self, deep: bool = True) -> dict:
        """The constructor's parameters and their current values."""
        return {name: getattr(self, name) for name in self._param_names()}

    def set_params(self, **params: Any) -> Self:
        """Set constructor parameters (checked when :meth:`fit` runs); returns ``self``."""
        valid = self._param_names()
        for name, value in params.items():
            if name not in valid:
                raise ValueRefused(f"{type(self).__name__} has no parameter {name!r} (parameters: {', '.join(valid)})")
            setattr(self, name, value)
        return self

    def __repr__(self) -> str:
        defaults = {p.name: p.default for p in inspect.signature(type(self).__init__).parameters.values()}
        changed = [f"{k}={v!r}" for k, v in self.get_params().items() if not _same(v, defaults.get(k))]
        return f"{type(self).__name__}({', '.join(changed)})"


def _same(a, b) -> bool:
    try:
        return bool(a is b or a == b)
    except (ValueError, TypeError):  # arrays and the like
        return False


def check_n_jobs(n_jobs: int | None) -> int:
    """Worker count from scikit-learn's ``n_jobs``: None -> 1, -1 -> every core, -2 -> all but one.

    A bool, a non-integer or 0 is refused with a one-line :class:`~ramure.errors.ValueRefused`.
    """
    if n_jobs is None:
        return 1
    if isinstance(n_jobs, bool):
        raise ValueRefused(f"n_jobs must be a whole number (1, 2, ..., or -1 for every core) or None, not the bool {n_jobs!r}")
    try:
        jobs = int(n_jobs)
    except (TypeError, ValueError):
        raise ValueRefused(f"n_jobs must be a whole number or None, not {n_jobs!r}") from None
    if jobs != n_jobs or jobs == 0:
        raise ValueRefused(
            f"n_jobs must be a whole number other than 0 (1, 2, ..., or -1 for every core) or None, not {n_jobs!r}"
        )
    if jobs < 0:
        jobs = max((os.cpu_count() or 1) + 1 + jobs, 1)
    return jobs


@functools.cache
def not_fitted_error() -> type[ValueRefused]:
    """The error of a method called before ``fit``: scikit-learn's ``NotFittedError`` and a
    :class:`~ramure.errors.ValueRefused` at once (scikit-learn is imported on first use only)."""
    from sklearn.exceptions import NotFittedError

    doc = "A method was called before fit (sklearn's NotFittedError, Ramure's ValueRefused)."
    return type("NotFitted", (ValueRefused, NotFittedError), {"__module__": __name__, "__doc__": doc})


def _column_names(X: Any) -> np.ndarray | None:
    """A data frame's column names when they are all strings (scikit-learn's rule), else None."""
    columns = getattr(X, "columns", None)
    if columns is None or not len(columns) or not all(isinstance(c, str) for c in columns):
        return None
    return np.asarray(list(columns), dtype=object)


def check_rows(estimator: ParamsMixin, X: Any, *, fitting: bool) -> np.ndarray:
    """``X`` as a 2-D float array (samples x features), refused in scikit-learn's words when sparse,
    complex, not 2-D or empty.  ``fitting=True`` records ``n_features_in_`` and
    ``feature_names_in_`` (a data frame's column names); otherwise the number of features and
    the names must match the fitted ones (a frame against a plain array only warns, as in
    scikit-learn)."""
    name = type(estimator).__name__
    if hasattr(X, "toarray") or type(X).__module__.startswith("scipy.sparse"):
        raise ValueRefused(f"{name} takes a dense array: sparse input is not supported (use X.toarray())")
    names = _column_names(X)
    X = np.asarray(X)
    if np.iscomplexobj(X):
        raise ValueRefused(f"Complex data not supported by {name}")
    X = X.astype(float)
    if X.ndim != 2:
        raise ValueRefused(
            f"{name} expected a 2-D array (samples x features), got shape {X.shape}; "
            "Reshape your data, e.g. a single sample with X.reshape(1, -1)"
        )
    if X.shape[0] == 0:
        raise ValueRefused(f"Found array with 0 sample(s) (shape={X.shape}) while a minimum of 1 is required by {name}.")
    if X.shape[1] == 0:
        raise ValueRefused(f"Found array with 0 feature(s) (shape={X.shape}) while a minimum of 1 is required by {name}.")
    if fitting:
        estimator.n_features_in_ = X.shape[1]  # type: ignore[attr-defined]
        if names is not None:
            estimator.feature_names_in_ = names  # type: ignore[attr-defined]
        elif hasattr(estimator, "feature_names_in_"):
            del estimator.feature_names_in_
        return X
    expected = estimator.n_features_in_  # type: ignore[attr-defined]
    if X.shape[1] != expected:
        raise ValueRefused(f"X has {X.shape[1]} features, but {name} is expecting {expected} features as input.")
    _check_names(name, getattr(estimator, "feature_names_in_", None), names)
    return X


def _check_names(name: str, fitted: np.ndarray | None, given: np.ndarray | None) -> None:
    if fitted is None and given is not None:
        warnings.warn(f"X has feature names, but {name} was fitted without feature names", UserWarning, stacklevel=3)
    elif fitted is not None and given is None:
        warnings.warn(f"X does not have valid feature names, but {name} was fitted with feature names", UserWarning, stacklevel=3)
    elif fitted is not None and given is not None and list(fitted) != list(given):
        raise ValueRefused(
            f"The feature names should match those that were passed during fit: fitted with {list(fitted)}, given {list(given)}"
        )
