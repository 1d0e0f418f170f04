"""Inference on the ratings with participants as the unit (statsmodels and scipy).

The thesis's ANOVA (:mod:`ramure.studies.anova`) runs on the 27 per-image means
of each grammar as if they were independent: its degrees of freedom, F(2, 78) for
three grammars, do not depend on how many people answered, so one participant
can be "significant".  Here each participant is one unit:

* :func:`rm_anova` -- repeated-measures ANOVA (statsmodels ``AnovaRM``) on each
  participant's mean rating per grammar, with partial eta squared and its 95 %
  CI (inverting the noncentral F);
* :func:`friedman` -- its rank-based counterpart (scipy), with Kendall's W;
* :func:`pairwise` -- paired contrasts between grammars: mean difference with
  its 95 % CI, Cohen's d_z with an exact CI (noncentral t), Holm-corrected p;
* :func:`mixed_model` -- a linear mixed model on every rated group (statsmodels
  ``MixedLM``): grammar fixed, random intercepts for the participant and for the
  test (the participant's pass over one grammar's pictures, the stimulus set);
* :func:`ordinal_model` -- a proportional-odds model (statsmodels ``OrderedModel``)
  on the same answers, treating the Likert levels as ordered categories, with
  standard errors clustered by participant (statsmodels has no random effects for
  it; a fixed effect per participant took 6-9 s at 100 participants).

A rated group is the answer unit: a rating is given to a group of images, not to
one image, so there is no image random effect on ratings; images enter through
the agreement of the groupings (:mod:`ramure.studies.agreement`).

Below :data:`MIN_PARTICIPANTS` complete participants, every result carries a
warning and no verdict is drawn; with one participant nothing can be tested.

>>> from ramure.studies.simulate import simulate_study
>>> r = rating_inference(simulate_study(participants=1, grammars=3, seed=0))
>>> r["usefulness"]["rm_anova"]["error"][:45], r["usefulness"]["significant"]
('needs at least 2 participants who rated every', False)
"""

from __future__ import annotations

import functools
import math
import warnings
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import pandas as pd

    from ramure.studies.data import StudyData

MEASURES = ("usefulness", "difference", "representative_quality")

#: Fewest participants (who rated every grammar) for an inference to be drawn.  It is the N at
#: which a paired comparison detects a large effect (Cohen's d_z = 0.8) with 80 % power at
#: alpha = 0.05 (statsmodels ``TTestPower().solve_power(0.8, power=0.8, alpha=0.05)`` = 14.3, so
#: 15).  Below it a non-significant result says nothing and the variance components of the mixed
#: model are poorly estimated; the numbers are shown, with a warning, and no verdict is drawn.
MIN_PARTICIPANTS = 15


def answers_frame(data: StudyData, measure: str) -> pd.DataFrame:
    """One row per rated group: participant, grammar, test, group and ``rating`` (1-4)."""
    import pandas as pd

    _check_measure(measure)
    rating = getattr(data, measure)
    keep = ~np.isnan(rating)
    frame = pd.DataFrame(
        dict(
            participant=np.asarray(data.participants, dtype=object)[data.test_participant[data.group_test]],
            grammar=np.asarray(data.grammars, dtype=object)[data.group_grammar],
            test=data.group_test,
            group=data.group_label,
            rating=rating,
        )
    )
    return frame[keep].reset_index(drop=True)


def participant_means(data: StudyData, measure: str) -> pd.DataFrame:
    """Each participant's mean rating of their groups, per grammar: participants x grammars.

    Only participants who rated groups of every grammar are kept (a repeated-measures
    design needs every cell); columns follow the study's grammar order.
    """
    frame = answers_frame(data, measure)
    wide = frame.groupby(["participant", "grammar"])["rating"].mean().unstack("grammar")
    wide = wide.reindex(columns=[g for g in data.grammars if g in wide.columns])
    return wide.dropna()


def rm_anova(wide: pd.DataFrame, alpha: float = 0.05) -> dict:
    """One-way repeated-measures ANOVA of ``wide`` (participants x conditions).

    The sums of squares in closed form (condition, participant, residual), F on
    (k - 1, (n - 1)(k - 1)) degrees of freedom, as statsmodels ``AnovaRM`` gives (a
    test fits it on the exported CSV) without its second of importing the formula
    machinery.  No sphericity correction: read Friedman's test beside it.
    """
    n, k = wide.shape
    if k < 2:
        return dict(error=f"needs at least 2 grammars rated, got {k}", n=n)
    if n < 2:
        return dict(error=f"needs at least 2 participants who rated every grammar, got {n}", n=n)
    from scipy.special import fdtrc

    y = wide.to_numpy(dtype=float)
    resid = y - y.mean(axis=1, keepdims=True) - y.mean(axis=0) + y.mean()
    ss_effect = float(n * ((y.mean(axis=0) - y.mean()) ** 2).sum())
    ss_error = float((resid**2).sum())
    df1, df2 = k - 1, (n - 1) * (k - 1)
    if ss_error > 1e-12 * max(ss_effect, 1.0):
        F = ss_effect / df1 / (ss_error / df2)
        p = float(fdtrc(df1, df2, F))
    else:
        F, p = (math.inf, 0.0) if ss_effect > 0 else (math.nan, math.nan)
    eta = ss_effect / (ss_effect + ss_error) if ss_effect + ss_error > 0 else math.nan
    low, high = _eta_ci(F, df1, df2) if math.isfinite(F) else (math.nan, math.nan)
    return dict(F=F, df1=df1, df2=df2, p=p, n=n, partial_eta2=eta, partial_eta2_ci=[low, high], means=_means(wide), alpha=alpha)


def friedman(wide: pd.DataFrame) -> dict:
    """Friedman's test of ``wide`` (participants x conditions, scipy) with Kendall's W.

    It needs three conditions or more; with two, read the paired contrast instead.
    """
    n, k = wide.shape
    if k < 3 or n < 2:
        return dict(error=f"needs at least 2 participants and 3 grammars, got {n} and {k}", n=n)
    from scipy.stats import friedmanchisquare

    with np.errstate(invalid="ignore", divide="ignore"):
        chi2, p = (float(v) for v in friedmanchisquare(*wide.to_numpy().T))
    return dict(chi2=chi2, df=k - 1, p=p, n=n, kendall_w=chi2 / (n * (k - 1)) if math.isfinite(chi2) else math.nan)


def pairwise(wide: pd.DataFrame, alpha: float = 0.05) -> list[dict]:
    """Paired contrasts of every pair of conditions of ``wide``, Holm-corrected (statsmodels).

    Each row: ``a``, ``b``, the mean of ``b - a`` with its 95 % t interval, t, df,
    p, ``p_holm`` and Cohen's d_z (mean difference over the SD of the differences)
    with its exact 95 % CI from the noncentral t.
    """
    from scipy.special import stdtr, stdtrit

    n, k = wide.shape
    if n < 2 or k < 2:
        return []
    names = list(wide.columns)
    rows = []
    for i in range(k):
        for j in range(i + 1, k):
            d = wide.iloc[:, j].to_numpy() - wide.iloc[:, i].to_numpy()
            mean, sd = float(d.mean()), float(d.std(ddof=1))
            se = sd / math.sqrt(n)
            t = mean / se if se > 0 else (math.copysign(math.inf, mean) if mean else math.nan)
            p = 2 * float(stdtr(n - 1, -abs(t))) if not math.isnan(t) else math.nan
            half = float(stdtrit(n - 1, 0.975)) * se
            dz = mean / sd if sd > 0 else math.nan
            rows.append(
                dict(
                    a=names[i], b=names[j], n=n, mean_difference=mean, ci=[mean - half, mean + half], t=t, df=n - 1, p=p,
                    d_z=dz, d_z_ci=list(_dz_ci(t, n)) if math.isfinite(t) else [math.nan, math.nan],
                )
            )  # fmt: skip
    ps = [r["p"] for r in rows]
    if all(math.isfinite(p) for p in ps):
        from statsmodels.stats.multitest import multipletests

        reject, holm, _, _ = multipletests(ps, alpha=alpha, method="holm")
        for r, h, rej in zip(rows, holm, reject):
            r.update(p_holm=float(h), reject=bool(rej))
    else:
        for r in rows:
            r.update(p_holm=math.nan, reject=False)
    return rows


def mixed_model(frame: pd.DataFrame, grammars: list[str]) -> dict:
    """Linear mixed model ``rating ~ grammar`` with participant and test random intercepts.

    ``frame`` is :func:`answers_frame`; ``grammars`` the order of the levels (the first
    is the reference).  Fitted by REML (statsmodels ``MixedLM``) twice, from statsmodels'
    start and from :func:`_moment_start`, keeping the larger REML likelihood: on a simulated
    100 x 7 study the two starts end at different optima for every measure (statsmodels' start
    on the boundary, a test variance near 0, and the lower likelihood for two of the three).
    The grammar effect is tested jointly by a Wald chi-square on its coefficients.
    """
    present = [g for g in grammars if g in set(frame["grammar"])]
    people = frame["participant"].nunique()
    if len(present) < 2 or people < 2:
        return dict(error=f"needs at least 2 participants and 2 grammars rated, got {people} and {len(present)}")
    from statsmodels.regression.mixed_linear_model import MixedLM, VCSpec

    df = frame.sort_values(["participant", "test"], kind="stable")  # MixedLM wants groups sorted
    exog = np.column_stack([np.ones(len(df)), *((df["grammar"] == g).to_numpy(float) for g in present[1:])])
    mats, colnames = [], []
    for _, rows in df.groupby("participant", sort=True)["test"]:
        codes = rows.to_numpy()
        levels = np.unique(codes)
        mats.append((codes[:, None] == levels[None, :]).astype(float))
        colnames.append([f"test {t}" for t in levels])
    model = MixedLM(
        df["rating"].to_numpy(float),
        exog,
        groups=df["participant"].to_numpy(),
        exog_re=np.ones((len(df), 1)),
        exog_vc=VCSpec(["test"], [colnames], [mats]),
    )
    rating = df["rating"].to_numpy(float)
    start = _moment_start(exog, rating, df["participant"].to_numpy(), df["test"].to_numpy())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fits = [model.fit(reml=True, method=["lbfgs", "powell"], start_params=s) for s in (None, start)]
    fit = max(fits, key=lambda f: f.llf)
    k = len(present)
    ci = np.asarray(fit.conf_int())
    wald = fit.wald_test(np.eye(len(fit.params))[1:k], scalar=True)
    return dict(
        n_answers=int(len(df)),
        n_participants=people,
        reference=present[0],
        effects=[
            dict(grammar=g, estimate=float(fit.fe_params[i]), ci=[float(v) for v in ci[i]], p=float(fit.pvalues[i]))
            for i, g in enumerate(present[1:], start=1)
        ],
        intercept=float(fit.fe_params[0]),
        wald_chi2=float(np.squeeze(wald.statistic)),
        wald_df=k - 1,
        p=float(wald.pvalue),
        variance=dict(participant=float(np.asarray(fit.cov_re)[0, 0]), test=float(fit.vcomp[0]), residual=float(fit.scale)),
        reml_log_likelihood=float(fit.llf),
        converged=bool(fit.converged),  # after the fall-back optimiser, if lbfgs failed
        boundary=any("boundary" in str(w.message) for w in caught),
    )


def _moment_start(exog: np.ndarray, y: np.ndarray, participant: np.ndarray, test: np.ndarray):
    """Start values for the mixed model: least-squares fixed effects and the variances of the
    residuals' participant means, test means within participants, and what is left (method of
    moments, ratios to the residual variance as MixedLM parametrises them): inside the
    parameter space, away from the boundary where statsmodels' own start may stop."""
    import pandas as pd
    from statsmodels.regression.mixed_linear_model import MixedLMParams

    beta = np.linalg.lstsq(exog, y, rcond=None)[0]
    frame = pd.DataFrame({"p": participant, "t": test, "r": y - exog @ beta})
    by_person = frame.groupby("p")["r"].transform("mean").to_numpy()
    by_test = frame.groupby(["p", "t"])["r"].transform("mean").to_numpy()
    residual = max(float(np.var(frame["r"].to_numpy() - by_test)), 1e-6)
    person = max(float(np.var(by_person)), 1e-3 * residual)
    within = max(float(np.var(by_test - by_person)), 1e-3 * residual)
    return MixedLMParams.from_components(
        fe_params=beta, cov_re=np.array([[person / residual]]), vcomp=np.array([within / residual])
    )


def ordinal_model(frame: pd.DataFrame, grammars: list[str]) -> dict:
    """Proportional-odds logit of the Likert levels on grammar, clustered by participant.

    A marginal (population-averaged) model: the grammar coefficients are log odds ratios
    of a higher answer against the first grammar, their standard errors the sandwich
    estimator clustered by participant, so the participants, not the answers, are the
    independent units.  ``odds_ratio`` and its 95 % CI exponentiate them; the grammar
    effect is tested jointly by Wald.
    """
    present = [g for g in grammars if g in set(frame["grammar"])]
    people = frame["participant"].nunique()
    levels = np.unique(frame["rating"])
    if len(present) < 2 or people < 2 or len(levels) < 2:
        return dict(error="needs at least 2 participants, 2 grammars and 2 levels used")
    import pandas as pd

    X = pd.DataFrame({f"grammar={g}": (frame["grammar"] == g).astype(float) for g in present[1:]})
    y = pd.Series(pd.Categorical(frame["rating"].astype(int), categories=levels, ordered=True))
    clusters = pd.factorize(frame["participant"])[0]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = _logit_model()(y, X, distr="logit")
        fit = model.fit(method="bfgs", disp=False, maxiter=500, cov_type="cluster", cov_kwds={"groups": clusters})
    terms = [f"grammar={g}" for g in present[1:]]
    ci = fit.conf_int()
    wald = fit.wald_test(np.eye(len(fit.params))[[list(fit.params.index).index(t) for t in terms]], scalar=True)
    return dict(
        reference=present[0],
        effects=[
            dict(
                grammar=t.split("=", 1)[1],
                log_odds=float(fit.params[t]),
                odds_ratio=math.exp(fit.params[t]),
                odds_ratio_ci=[math.exp(v) for v in ci.loc[t]],
                p=float(fit.pvalues[t]),
            )
            for t in terms
        ],  # fmt: skip
        wald_chi2=float(wald.statistic),
        wald_df=len(terms),
        p=float(wald.pvalue),
        converged=bool(fit.mle_retvals.get("converged", True)) and not any(_failed(w) for w in caught),
    )


def rating_inference(data: StudyData, alpha: float = 0.05, measures: tuple[str, ...] = MEASURES, models: bool = True) -> dict:
    """Every participant-level test of each rated measure, with warnings and a verdict.

    ``significant`` is True only when the repeated-measures ANOVA rejects at ``alpha``
    with at least :data:`MIN_PARTICIPANTS` complete participants (the mixed model's
    Wald test, with that many participants, when too few rated every grammar).  ``models`` False
    skips the mixed and ordinal models (the slow part).
    """
    out: dict = dict(alpha=alpha, min_participants=MIN_PARTICIPANTS, unit="participant")
    for measure in measures:
        wide = participant_means(data, measure)
        frame = answers_frame(data, measure)
        res: dict = dict(n=int(len(wide)), dropped=sorted(set(frame["participant"]) - set(wide.index)))
        res["rm_anova"] = rm_anova(wide, alpha)
        res["friedman"] = friedman(wide)
        res["pairwise"] = pairwise(wide, alpha)
        if models:
            res["mixed_model"] = _guarded(mixed_model, frame, list(data.grammars))
            res["ordinal_model"] = _guarded(ordinal_model, frame, list(data.grammars))
        res["warnings"] = _warnings(res)
        res["verdict"], p, n = _verdict(res, alpha)
        res["significant"] = bool(p is not None and p < alpha and n >= MIN_PARTICIPANTS)
        out[measure] = res
    return out


# -- helpers ---------------------------------------------------------------------
@functools.cache
def _logit_model():
    """statsmodels' ``OrderedModel(distr="logit")`` with its gradient in closed form.

    Same model, likelihood and optimiser; the stock model differentiates the likelihood
    numerically (two evaluations per parameter per step, and a numerical Hessian), which
    took 3 s for 20 participants with a parameter each.  The Hessian is the numerical
    derivative of this gradient.  A test compares the fit with the stock model.
    """
    from scipy.special import expit
    from statsmodels.miscmodels.ordinal_model import OrderedModel
    from statsmodels.tools.numdiff import approx_fprime

    class ClosedFormLogit(OrderedModel):
        def cdf(self, x):
            return expit(x)

        def pdf(self, x):
            e = expit(x)
            return e * (1 - e)

        def score(self, params):
            params = np.asarray(params, dtype=float)
            k, levels = self.exog.shape[1], self.k_levels
            thresh = self.transform_threshold_params(params)
            y = np.asarray(self.endog, dtype=np.int64)
            xb = self.exog @ params[:k]
            upper, lower = self.cdf(thresh[y + 1] - xb), self.cdf(thresh[y] - xb)
            prob = upper - lower + 1e-20  # as loglikeobs
            dens_up, dens_low = upper * (1 - upper) / prob, lower * (1 - lower) / prob
            d_beta = -(self.exog.T @ (dens_up - dens_low))
            # g[j]: derivative in threshold j (0 .. levels - 2), reached as the upper bound of
            # answers j and the lower bound of answers j + 1.
            g = np.bincount(y, dens_up, levels + 1)[: levels - 1] - np.bincount(y, dens_low, levels + 1)[1:levels]
            tail = np.cumsum(g[::-1])[::-1]  # sum of g[j] for j >= m
            return np.concatenate([d_beta, tail[:1], np.exp(params[k + 1 :]) * tail[1:]])

        def hessian(self, params):
            h = approx_fprime(np.asarray(params, dtype=float), self.score, centered=True)
            return (h + h.T) / 2

    return ClosedFormLogit


def _check_measure(measure):
    if measure not in MEASURES:
        from ramure.studies.errors import StudyInputError

        raise StudyInputError(f"unknown measure {measure!r} (choose from {', '.join(MEASURES)})")


def _means(wide):
    return {str(g): dict(mean=float(wide[g].mean()), sd=float(wide[g].std(ddof=1))) for g in wide.columns}


def _failed(caught):
    """A warning that an optimiser failed (not the note that a variance sits on the boundary, 0)."""
    from statsmodels.tools.sm_exceptions import ConvergenceWarning

    return issubclass(caught.category, ConvergenceWarning) and "boundary" not in str(caught.message)


def _guarded(fit, frame, grammars):
    """A model fit whose numerical failure (singular design, no variance) is reported, not raised."""
    try:
        return fit(frame, grammars)
    except (np.linalg.LinAlgError, ValueError) as exc:
        return dict(error=f"could not be fitted: {exc}")


def _warnings(res):
    n = res["n"]
    out = []
    if n < 2:
        out.append(f"{n} participant(s) rated every grammar: the repeated-measures tests cannot run.")
    elif n < MIN_PARTICIPANTS:
        out.append(
            f"only {n} participants rated every grammar (minimum {MIN_PARTICIPANTS}, the N that detects a large "
            "effect, d_z = 0.8, with 80 % power): the tests are exploratory and no verdict is drawn."
        )
    if res["dropped"]:
        out.append(f"{len(res['dropped'])} participant(s) left out of the ANOVA for not rating every grammar.")
    for key in ("mixed_model", "ordinal_model"):
        if key in res and not res[key].get("error") and not res[key].get("converged", True):
            out.append(f"the {key.replace('_', ' ')} did not converge cleanly; read its estimates with care.")
    return out


def _verdict(res, alpha):
    """(verdict text, p, N) of the repeated-measures ANOVA; when some participants did not rate
    every grammar so that it cannot run, of the mixed model, which uses every answer."""
    a, m = res["rm_anova"], res.get("mixed_model") or {}
    if "error" not in a:
        stats, p, n = f"F({a['df1']:g}, {a['df2']:g}) = {a['F']:.2f}, p = {a['p']:.3g}", a["p"], res["n"]
    elif m and "error" not in m:
        p, n = m["p"], m["n_participants"]
        stats = f"mixed model (not everyone rated every grammar): Wald χ²({m['wald_df']}) = {m['wald_chi2']:.2f}, p = {p:.3g}"
    else:
        return f"not tested: {a['error']}", None, res["n"]
    if math.isnan(p):
        return "undefined: every participant gave the same means", None, n
    if n < MIN_PARTICIPANTS:
        return f"{stats}; N = {n} is below {MIN_PARTICIPANTS}: exploratory, no verdict", p, n
    if p < alpha:
        return f"{stats}: the grammars differ (alpha = {alpha:g})", p, n
    return f"{stats}: no evidence that the grammars differ (alpha = {alpha:g})", p, n


def _eta_ci(F, df1, df2, level=0.95):
    """CI of partial eta squared by inverting the noncentral F in its noncentrality (Steiger 2004)."""
    from scipy.optimize import brentq
    from scipy.special import ncfdtr

    def cdf(lam):
        value = float(ncfdtr(df1, df2, lam, F))
        return 0.0 if math.isnan(value) else value  # NaN only where the cdf underflows, far right

    def bound(q):
        if cdf(0.0) < q:
            return 0.0
        hi = max(10.0, 2 * F * df1)
        while cdf(hi) > q and hi < 1e7:
            hi *= 2
        return brentq(lambda lam: cdf(lam) - q, 0.0, hi)

    tail = (1 - level) / 2
    lams = bound(1 - tail), bound(tail)
    total = df1 + df2 + 1
    return tuple(float(lam / (lam + total)) for lam in lams)


def _dz_ci(t, n, level=0.95):
    """Exact CI of Cohen's d_z = t / sqrt(n) from the noncentral t (NaN where it cannot be bracketed)."""
    from scipy.optimize import brentq
    from scipy.special import nctdtr

    df, tail = n - 1, (1 - level) / 2

    def bound(q):
        f = lambda nc: nctdtr(df, nc, t) - q  # noqa: E731
        lo, hi, step = t - 1.0, t + 1.0, 1.0
        while f(lo) < 0 or f(hi) > 0:  # cdf falls as nc grows: bracket the root
            step *= 2
            lo, hi = t - step, t + step
            if step > 1e4 or math.isnan(f(lo)) or math.isnan(f(hi)):
                return math.nan
        return brentq(f, lo, hi)

    return bound(1 - tail) / math.sqrt(n), bound(tail) / math.sqrt(n)
