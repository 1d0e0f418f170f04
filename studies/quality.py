"""The answers the ratings leave out: time on task, data-quality flags, representatives.

* :func:`per_test_quality` -- one row per test: time on task, groups formed, share of
  groups fully rated, and flags a reviewer asks about:

  - ``too_fast``: under :data:`TOO_FAST_SECONDS` or under a third of the study's
    median test time (sorting 27 pictures, rating and naming each group cannot be
    done with care faster);
  - ``single_group``: every picture in one group (no sorting);
  - ``all_alone``: every picture in a group of its own (no sorting either);
  - ``straight_lining``: three groups or more, every usefulness and difference
    answer the same level;
  - ``unrated``: some group lacks a usefulness or difference answer;
  - ``missed_attention``: the participant answered an attention check with another option
    than the one it asked for (every test of that participant carries the flag).

* :func:`quality_summary` -- time on task per grammar and the flag counts;
* :func:`representatives` -- how often the chosen representative is the group's
  medoid (the image nearest the group's centre in PCA space) against the chance
  rate of picking at random, and the representative rating either way.

>>> from ramure.studies.simulate import simulate_study
>>> data = simulate_study(participants=3, grammars=1, seed=0)
>>> rows = per_test_quality(data)
>>> len(rows), rows[0]["seconds"] > 60, any(r["flags"] for r in rows)
(3, True, False)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ramure.studies.analysis import summary

if TYPE_CHECKING:
    from ramure.studies.data import StudyData

TOO_FAST_SECONDS = 60.0
FLAGS = ("too_fast", "single_group", "all_alone", "straight_lining", "unrated", "missed_attention")


def per_test_quality(data: StudyData) -> list[dict]:
    """One dict per test: participant, grammar, seconds, groups, rated share and ``flags``."""
    n = data.n_tests
    seconds = data.test_seconds if len(data.test_seconds) == n else np.full(n, np.nan)
    slow_enough = (
        max(TOO_FAST_SECONDS, float(np.nanmedian(seconds)) / 3) if n and np.isfinite(seconds).any() else TOO_FAST_SECONDS
    )
    groups = np.bincount(data.group_test, minlength=n)
    rated = ~np.isnan(data.usefulness) & ~np.isnan(data.difference)
    rated_groups = np.bincount(data.group_test, weights=rated, minlength=n)
    missed = data.attention_missed if len(data.attention_missed) == len(data.participants) else None
    rows = []
    for t in range(n):
        mine = data.group_test == t
        levels = np.concatenate([data.usefulness[mine], data.difference[mine]])
        flags = dict(
            too_fast=bool(seconds[t] < slow_enough),
            single_group=bool(groups[t] == 1),
            all_alone=bool(groups[t] == data.membership.shape[1]),
            straight_lining=bool(groups[t] >= 3 and rated[mine].all() and np.unique(levels).size == 1),
            unrated=bool(rated_groups[t] < groups[t]),
            missed_attention=bool(missed is not None and missed[data.test_participant[t]] > 0),
        )
        rows.append(
            dict(
                participant=data.participants[data.test_participant[t]],
                grammar=data.grammars[data.test_grammar[t]],
                seconds=float(seconds[t]),
                groups=int(groups[t]),
                rated_share=float(rated_groups[t] / groups[t]) if groups[t] else 0.0,
                flags=[f for f in FLAGS if flags[f]],
            )
        )
    return rows


def quality_summary(data: StudyData) -> dict:
    """Time on task (seconds) per grammar and overall, the flag counts, and the flagged tests."""
    rows = per_test_quality(data)
    time = {g: summary([r["seconds"] for r in rows if r["grammar"] == g and np.isfinite(r["seconds"])]) for g in data.grammars}
    time["all"] = summary([r["seconds"] for r in rows if np.isfinite(r["seconds"])])
    return dict(
        too_fast_seconds=TOO_FAST_SECONDS,
        time_on_task=time,
        flag_counts={f: sum(f in r["flags"] for r in rows) for f in FLAGS},
        flagged=[r for r in rows if r["flags"]],
        participants_flagged=sorted({r["participant"] for r in rows if r["flags"]}),
    )


def representatives(data: StudyData) -> dict:
    """Medoid share of the chosen representatives per grammar, against chance.

    Only groups of two images or more with a representative count.  ``chance`` is the
    mean of 1 / group size (picking at random); ``quality_medoid`` and
    ``quality_other`` the mean representative rating (1-4) of each kind of choice.
    """
    out = {}
    for gi, grammar in enumerate(data.grammars):
        unit = data.pca[gi]  # PCA distances as they are: the axes share one unit
        rows = np.flatnonzero((data.group_grammar == gi) & (data.representative > 0) & (data.membership.sum(axis=1) >= 2))
        medoid, chance = [], []
        for g in rows:
            members = np.flatnonzero(data.membership[g])
            dist = np.linalg.norm(unit[members] - unit[members].mean(axis=0), axis=1)
            medoid.append(members[np.argmin(dist)] + 1 == data.representative[g])
            chance.append(1 / len(members))
        is_medoid = np.array(medoid, dtype=bool)
        quality = data.representative_quality[rows]
        out[grammar] = dict(
            groups=int(len(rows)),
            medoid_share=float(is_medoid.mean()) if len(rows) else None,
            chance=float(np.mean(chance)) if len(rows) else None,
            quality_medoid=_nanmean(quality[is_medoid]),
            quality_other=_nanmean(quality[~is_medoid]),
        )
    return out


def _nanmean(values):
    values = values[~np.isnan(values)]
    return float(values.mean()) if len(values) else None
