"""User studies on variant relevance (thesis §7): sessions, storage, analysis, reports.

A study is a set of grammars, each with its 27 picked variants, and
participants who each do one test per grammar: sort the 27 images into
groups, choose representatives, rate groups on 4-level Likert scales and name
them.  Everything is stored in SQLite, one transaction per answer.

>>> import tempfile, pathlib
>>> from ramure.studies import Study, lattice_picks, load_study_data, cooccurrence
>>> study = Study.create(pathlib.Path(tempfile.mkdtemp()) / "s.db", grammars={"honda": lattice_picks()})
>>> s = study.session(study.add_participant(consent=True), "honda")
>>> s.set_groups([range(1, 14), range(14, 28)])
>>> for g in (1, 2):
...     s.set_representative(g, 14 if g == 2 else 1)
...     s.rate(g, usefulness="good", difference="fair", representative="excellent")
...     s.add_qualifier(g, "petit" if g == 1 else "grand")
>>> s.finish()
>>> int(cooccurrence(load_study_data(study))[0, 12]), int(cooccurrence(load_study_data(study))[0, 13])
(1, 0)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ramure.lazy import lazy_loader

if TYPE_CHECKING:
    from ramure.studies.analysis import cooccurrence, grouping_stats, groups_per_test, image_ratings, images_per_group
    from ramure.studies.anova import AnovaResult, anova_table, one_way_anova, read_table
    from ramure.studies.data import StudyData, load_study_data
    from ramure.studies.design import ParticipantFlow, StudyConfig, read_config
    from ramure.studies.errors import StudyInputError
    from ramure.studies.agreement import grouping_agreement, pairwise_ari
    from ramure.studies.export import export_csv, write_codebook
    from ramure.studies.inference import rating_inference
    from ramure.studies.quality import quality_summary, representatives, per_test_quality
    from ramure.studies.likert import LEVELS, likert_value
    from ramure.studies.picks import Pick, lattice_picks, load_picks, picks_from_data, synthetic_grammars
    from ramure.studies.qualifiers import (
        SynonymTable,
        export_qualifier_points,
        labelled_points,
        normalise_text,
        qualifier_frequencies,
    )
    from ramure.studies.report import analyze, write_report
    from ramure.studies.session import Group, TestSession, image_order
    from ramure.studies.simulate import SimulatedParticipant, run_simulation, simulate_study
    from ramure.studies.storage import Study, connect

# name -> submodule of ramure.studies that defines it, imported on first use (ramure.lazy): ``ramure study
# anova`` then loads only the ANOVA module, not the report's matplotlib, metrics and scipy.
_LAZY = {
    "AnovaResult": ".anova",
    "Group": ".session",
    "LEVELS": ".likert",
    "ParticipantFlow": ".design",
    "Pick": ".picks",
    "SimulatedParticipant": ".simulate",
    "Study": ".storage",
    "StudyConfig": ".design",
    "StudyData": ".data",
    "StudyInputError": ".errors",
    "SynonymTable": ".qualifiers",
    "TestSession": ".session",
    "analyze": ".report",
    "anova_table": ".anova",
    "connect": ".storage",
    "cooccurrence": ".analysis",
    "export_csv": ".export",
    "export_qualifier_points": ".qualifiers",
    "grouping_agreement": ".agreement",
    "grouping_stats": ".analysis",
    "groups_per_test": ".analysis",
    "image_order": ".session",
    "image_ratings": ".analysis",
    "images_per_group": ".analysis",
    "labelled_points": ".qualifiers",
    "lattice_picks": ".picks",
    "likert_value": ".likert",
    "load_picks": ".picks",
    "load_study_data": ".data",
    "normalise_text": ".qualifiers",
    "one_way_anova": ".anova",
    "pairwise_ari": ".agreement",
    "per_test_quality": ".quality",
    "picks_from_data": ".picks",
    "qualifier_frequencies": ".qualifiers",
    "quality_summary": ".quality",
    "rating_inference": ".inference",
    "read_config": ".design",
    "read_table": ".anova",
    "representatives": ".quality",
    "run_simulation": ".simulate",
    "simulate_study": ".simulate",
    "synthetic_grammars": ".picks",
    "write_codebook": ".export",
    "write_report": ".report",
}

__all__ = [
    "AnovaResult",
    "Group",
    "LEVELS",
    "ParticipantFlow",
    "Pick",
    "SimulatedParticipant",
    "Study",
    "StudyConfig",
    "StudyData",
    "StudyInputError",
    "SynonymTable",
    "TestSession",
    "analyze",
    "anova_table",
    "connect",
    "cooccurrence",
    "export_csv",
    "export_qualifier_points",
    "grouping_agreement",
    "grouping_stats",
    "groups_per_test",
    "image_order",
    "image_ratings",
    "images_per_group",
    "labelled_points",
    "lattice_picks",
    "likert_value",
    "load_picks",
    "load_study_data",
    "normalise_text",
    "one_way_anova",
    "pairwise_ari",
    "per_test_quality",
    "picks_from_data",
    "qualifier_frequencies",
    "quality_summary",
    "rating_inference",
    "read_config",
    "read_table",
    "representatives",
    "run_simulation",
    "simulate_study",
    "synthetic_grammars",
    "write_codebook",
    "write_report",
]


_load, _names = lazy_loader(__name__, _LAZY)


def __getattr__(name: str) -> object:
    return _load(name)


def __dir__() -> list[str]:
    return _names()
